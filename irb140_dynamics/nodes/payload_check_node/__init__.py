"""payload_check_node: can the arm hold this payload (``node``; ~/check waiting for the
analysis of new parameters: ``check_service``); what is on the flange (``payload_estimator``)."""
