"""sim_node: the arm simulated in MuJoCo (``sim``), behind ROS topics."""
