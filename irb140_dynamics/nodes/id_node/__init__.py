"""id_node: live inverse dynamics, gravity compensation, computed torque, collisions."""

from irb140_dynamics.nodes import quiet_ctrl_c


def main() -> None:
    """The console script ``id_node`` (``ros2 run irb140_dynamics id_node``)."""
    with quiet_ctrl_c():
        from irb140_dynamics.nodes.id_node.node import main as node_main
    node_main()
