"""export_urdf: print the current model as URDF (the IRB-140's with the report's shapes).

    ros2 run irb140_dynamics export_urdf [--ros-args --params-file FILE -p NAME:=VALUE ...] > arm.urdf

The model is read as the nodes read it (the default config/irb140.yaml, then the params
file, then -p; ``model.source:=robot_description`` with ``robot_description`` or
``model.urdf_file`` works too, the topic does not), in a node named ``export_urdf`` that
is never spun: parameters under ``/**`` in a params file apply, those under a node's name
do not. The URDF goes to stdout; a bad parameter is one line on stderr and exit code 1.
"""

from __future__ import annotations

import sys

from irb140_dynamics.core import RobotModel, irb140
from irb140_dynamics.core.io.urdf import export_urdf
from irb140_dynamics.core.model.irb140 import IRB140_SHAPES
from irb140_dynamics.ros.parameters.model_source import model_from_arguments
from irb140_dynamics.ros.runtime.spin import tool_arguments

NAME = "export_urdf"


def urdf_of(model: RobotModel) -> str:
    """The model's URDF; with the IRB-140's joints, named irb140 and drawn with its shapes."""
    if model.joint_names == irb140().joint_names:
        return export_urdf(model, "irb140", IRB140_SHAPES)
    return export_urdf(model, "robot")


def main(args: list[str] | None = None) -> int:
    args = sys.argv if args is None else args
    try:
        extra = tool_arguments(args)
        if extra:
            help_asked = extra[0] in ("-h", "--help")
            print(
                __doc__ if help_asked else f"{NAME}: unknown arguments {extra}; see --help",
                file=sys.stdout if help_asked else sys.stderr,
            )
            return 0 if help_asked else 2
        text = urdf_of(model_from_arguments(args, NAME))
    except ValueError as error:
        return _fail(str(error))
    sys.stdout.write(text)
    return 0


def _fail(reason: str) -> int:
    print(f"{NAME}: {reason.replace(chr(10), ' ')}", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
