"""payload_check_node: can the arm hold this payload; what is on the flange."""

from irb140_dynamics.nodes import start


def main() -> None:
    """The console script ``payload_check_node`` (``ros2 run irb140_dynamics payload_check_node``)."""
    start("irb140_dynamics.nodes.payload_check_node.node")
