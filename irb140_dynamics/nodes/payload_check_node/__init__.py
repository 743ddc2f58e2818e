"""payload_check_node: can the arm hold this payload; what is on the flange."""
