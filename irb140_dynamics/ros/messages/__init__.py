"""Messages <-> arrays in the model's joint order: JointState and JointTrajectory read and
checked (``joint_messages``), JointState as CDR bytes for id_node's hot path
(``joint_state_cdr``)."""
