"""demo_node: a first look at the closed loop (a reference motion, the tracking error)."""

from irb140_dynamics.entry import NODE, finish, start


def main() -> None:
    """``demo_node`` as ``ros2 run`` and ``python -m irb140_dynamics.nodes.demo_node`` start it:
    the node's main() through the entry (irb140_dynamics.entry)."""
    start("demo_node", NODE)
    from irb140_dynamics.nodes.demo_node.node import main as node_main

    finish(node_main)
