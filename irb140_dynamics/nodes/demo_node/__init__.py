"""demo_node: a first look at the closed loop (a reference motion, the tracking error)."""
