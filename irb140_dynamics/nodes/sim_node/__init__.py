"""sim_node: the arm simulated in MuJoCo (``sim``), behind ROS topics."""

from irb140_dynamics.entry import NODE, finish, start


def main() -> None:
    """``sim_node`` as ``ros2 run`` and ``python -m irb140_dynamics.nodes.sim_node`` start it:
    the node's main() through the entry (irb140_dynamics.entry)."""
    start("sim_node", NODE)
    from irb140_dynamics.nodes.sim_node.node import main as node_main

    finish(node_main)
