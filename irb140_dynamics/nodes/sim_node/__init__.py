"""sim_node: the arm simulated in MuJoCo (``sim``), behind ROS topics."""

from irb140_dynamics.nodes import start


def main() -> None:
    """The console script ``sim_node`` (``ros2 run irb140_dynamics sim_node``)."""
    start("irb140_dynamics.nodes.sim_node.node")
