"""payload_check_node: can the arm hold this payload (``node``; ~/check waiting for the
analysis of new parameters: ``check_service``); what is on the flange (``payload_estimator``)."""

from irb140_dynamics.nodes import quiet_ctrl_c


def main() -> None:
    """The console script ``payload_check_node`` (``ros2 run irb140_dynamics payload_check_node``)."""
    with quiet_ctrl_c():
        from irb140_dynamics.nodes.payload_check_node.node import main as node_main
    node_main()
