"""trajectory_check_node: JointTrajectories checked against the arm's limits and re-timed
(``node``; the checks are core.trajectories', the messages ros.messages')."""

from irb140_dynamics.entry import NODE, finish, start


def main() -> None:
    """``trajectory_check_node`` as ``ros2 run`` and ``python -m irb140_dynamics.nodes.trajectory_check_node`` start it:
    the node's main() through the entry (irb140_dynamics.entry)."""
    start("trajectory_check_node", NODE)
    from irb140_dynamics.nodes.trajectory_check_node.node import main as node_main

    finish(node_main)
