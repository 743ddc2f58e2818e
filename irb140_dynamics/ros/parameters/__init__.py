"""A node's parameters on rclpy's public API: one ``spec``, the shared ``specs``, the values
given at startup (``overrides``), a node's ``arm``, the parameter ``services``, ``--help``'s
model sections (``usage``)."""
