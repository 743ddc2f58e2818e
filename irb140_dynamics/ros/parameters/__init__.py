"""Parameters of the nodes: one parameter (``spec``), the shared catalogues of model and
QoS parameters and their checks (``specs``), parameters kept live and validated whole
(``live``), where the model comes from (``model_source``: parameters or URDF), the guarded
parameter services (``services``), and the warning about unknown ones (``overrides``,
``catalog``)."""
