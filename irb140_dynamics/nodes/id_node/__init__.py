"""id_node: live inverse dynamics, gravity compensation, computed torque, collisions."""

from irb140_dynamics.nodes import start


def main() -> None:
    """The console script ``id_node`` (``ros2 run irb140_dynamics id_node``)."""
    start("irb140_dynamics.nodes.id_node.node")
