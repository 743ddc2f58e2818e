"""id_node: live inverse dynamics, gravity compensation, computed torque, collisions."""

from irb140_dynamics.entry import NODE, finish, start


def main() -> None:
    """``id_node`` as ``ros2 run`` and ``python -m irb140_dynamics.nodes.id_node`` start it:
    the node's main() through the entry (irb140_dynamics.entry)."""
    start("id_node", NODE)
    from irb140_dynamics.nodes.id_node.node import main as node_main

    finish(node_main)
