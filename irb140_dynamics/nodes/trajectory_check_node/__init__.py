"""trajectory_check_node: JointTrajectories checked against the arm's limits and re-timed
(see ``node``); ``messages``: JointTrajectory messages to and from the core's Trajectory and
the report as a DiagnosticStatus.

May import: ``core``, ``ros``; never another node.
"""
