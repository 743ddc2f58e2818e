"""payload_check_node: can the arm hold this payload, and what is on the flange (``node``)."""
