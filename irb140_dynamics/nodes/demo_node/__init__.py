"""demo_node: a first look at the closed loop (a reference motion, the tracking error)."""

from irb140_dynamics.nodes import quiet_ctrl_c


def main() -> None:
    """The console script ``demo_node`` (``ros2 run irb140_dynamics demo_node``)."""
    with quiet_ctrl_c():
        from irb140_dynamics.nodes.demo_node.node import main as node_main
    node_main()
