"""Parameters of the nodes, on rclpy's public API: one parameter and its descriptor
(``spec``), the values given at startup (``overrides``), the parameters every node shares
(``specs``), a node's arm and its own parameters (``arm``: parameters or URDF), the
parameter services (``services``), the names of the nodes' own parameters (``catalog``)
and ``--help``'s model sections (``usage``)."""
