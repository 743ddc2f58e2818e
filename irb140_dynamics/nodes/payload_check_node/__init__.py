"""payload_check_node: can the arm hold this payload, and what is on the flange (``node``)."""

from irb140_dynamics.entry import NODE, finish, start


def main() -> None:
    """``payload_check_node`` as ``ros2 run`` and ``python -m irb140_dynamics.nodes.payload_check_node`` start it:
    the node's main() through the entry (irb140_dynamics.entry)."""
    start("payload_check_node", NODE)
    from irb140_dynamics.nodes.payload_check_node.node import main as node_main

    finish(node_main)
