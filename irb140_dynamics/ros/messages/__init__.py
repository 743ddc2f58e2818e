"""Joint messages <-> arrays in the model's joint order (``joint_messages``), JointState as CDR
bytes (``joint_state_cdr``), flange wrenches (``wrench``)."""
