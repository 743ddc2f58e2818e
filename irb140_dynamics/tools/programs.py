"""The tools' console scripts (setup.py: ``<tool>`` for ``ros2 run``, ``irb140-<tool>`` for a
PyPI install): each starts the entry (irb140_dynamics.entry) before it imports its tool,
then runs the tool's main(). Light: importing this module imports no tool."""

from irb140_dynamics.entry import RECORDER, TOOL, finish, start


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
