"""id_node: live inverse dynamics, gravity compensation, computed torque, collisions."""
