"""Every executable's console script (setup.py): a node's name, a tool's plain name for ``ros2
run`` and its ``irb140-<tool>`` name for a PyPI install (``python -c "from
irb140_dynamics.programs import id_node; id_node()"`` from a checkout). Each starts the entry
(irb140_dynamics.entry) before it imports its node or tool, then runs that one's main().
Light: importing this module imports no node and no tool."""

from irb140_dynamics.entry import NODE, RECORDER, TOOL, finish, start


def id_node() -> None:
    start("id_node", NODE)
    from irb140_dynamics.nodes.id_node.node import main

    finish(main)


def payload_check_node() -> None:
    start("payload_check_node", NODE)
    from irb140_dynamics.nodes.payload_check_node.node import main

    finish(main)


def sim_node() -> None:
    start("sim_node", NODE)
    from irb140_dynamics.nodes.sim_node.node import main

    finish(main)


def demo_node() -> None:
    start("demo_node", NODE)
    from irb140_dynamics.nodes.demo_node.node import main

    finish(main)


def trajectory_check_node() -> None:
    start("trajectory_check_node", NODE)
    from irb140_dynamics.nodes.trajectory_check_node.node import main

    finish(main)


def equations() -> None:
    start("equations", TOOL)
    from irb140_dynamics.tools.equations import main

    finish(main)


def excitation() -> None:
    start("excitation", TOOL)
    from irb140_dynamics.tools.excitation import main

    finish(main)


def export_urdf() -> None:
    start("export_urdf", TOOL)
    from irb140_dynamics.tools.export_urdf import main

    finish(main)


def identify() -> None:
    start("identify", TOOL)
    from irb140_dynamics.tools.identify import main

    finish(main)


def load_diagram() -> None:
    start("load_diagram", TOOL)
    from irb140_dynamics.tools.load_diagram import main

    finish(main)


def record() -> None:
    start("record", RECORDER)
    from irb140_dynamics.tools.record import main

    finish(main)


def retime() -> None:
    start("retime", TOOL)
    from irb140_dynamics.tools.retime import main

    finish(main)


def calibrate_collision() -> None:
    start("calibrate_collision", TOOL)
    from irb140_dynamics.tools.calibrate_collision import main

    finish(main)
