"""trajectory_check_node: JointTrajectories checked against the arm's limits and re-timed
(see ``node``); ``messages``: JointTrajectory messages to and from the core's Trajectory and
the report as a DiagnosticStatus.

May import: ``core``, ``ros``; never another node.
"""

from irb140_dynamics.nodes import quiet_ctrl_c


def main() -> None:
    """The console script ``trajectory_check_node`` (``ros2 run irb140_dynamics trajectory_check_node``)."""
    with quiet_ctrl_c():
        from irb140_dynamics.nodes.trajectory_check_node.node import main as node_main
    node_main()
