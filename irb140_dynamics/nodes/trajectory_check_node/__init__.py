"""trajectory_check_node: JointTrajectories checked against the arm's limits and re-timed (``node``; the checks are core.trajectories', the messages ros.messages')."""
