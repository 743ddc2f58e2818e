"""sim_node: the arm simulated in MuJoCo (``sim``), behind ROS topics."""

from irb140_dynamics.nodes import quiet_ctrl_c


def main() -> None:
    """The console script ``sim_node`` (``ros2 run irb140_dynamics sim_node``)."""
    with quiet_ctrl_c():
        from irb140_dynamics.nodes.sim_node.node import main as node_main
    node_main()
