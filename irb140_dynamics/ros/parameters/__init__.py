"""Parameters of the nodes, on rclpy's public API: one parameter and its descriptor
(``spec``), the values given at startup (``overrides``), the parameters every node shares
(``specs``), a node's arm and its own parameters (``arm``: parameters or URDF), the
parameter services (``services``) and ``--help``'s model sections (``usage``). The names of
the nodes' own parameters are below, in ``core.io.parameter_names`` (the tools know them
too)."""
