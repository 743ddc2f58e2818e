"""export_urdf: print a model as URDF (the IRB-140's with the report's shapes).

    ros2 run irb140_dynamics export_urdf [--params-file FILE | --urdf FILE [--base LINK] [--tip LINK]]
                                         [-p NAME:=VALUE ...] > arm.urdf

The model is read as the other tools read it (``core.io.model_source``): the default
config/irb140.yaml, then the params file (``model.source: robot_description`` with
``robot_description`` or ``model.urdf_file`` works too), then -p; or a URDF's chain. The
ROS form ``--ros-args --params-file FILE -p NAME:=VALUE`` is taken as well (parameters
under ``/**`` in a params file apply). No ROS needed. The URDF goes to stdout; a bad
parameter or file is one line on stderr and exit code 1.
"""

from __future__ import annotations

import argparse
import sys

from irb140_dynamics.core import RobotModel, irb140
from irb140_dynamics.core.io.urdf import export_urdf
from irb140_dynamics.core.model.irb140 import IRB140_SHAPES
from irb140_dynamics.tools.common import add_model_arguments, model_of

NAME = "export_urdf"
ROS_MARKERS = ("--ros-args", "--")  # the ROS form's markers: its --params-file and -p are ours


def urdf_of(model: RobotModel) -> str:
    """The model's URDF; with the IRB-140's joints, named irb140 and drawn with its shapes."""
    if model.joint_names == irb140().joint_names:
        return export_urdf(model, "irb140", IRB140_SHAPES)
    return export_urdf(model, "robot")


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):
        print(f"{NAME}: {message}; see --help", file=sys.stderr)
        sys.exit(2)


def parser() -> argparse.ArgumentParser:
    p = _Parser(prog=NAME, description=__doc__.split("\n\n")[0].split(": ", 1)[1])
    add_model_arguments(p)
    return p


def main(args: list[str] | None = None) -> int:
    args = sys.argv if args is None else args
    arguments = parser().parse_args([a for a in args[1:] if a not in ROS_MARKERS])
    try:
        text = urdf_of(model_of(arguments).model)
    except ValueError as error:
        print(f"{NAME}: {str(error).replace(chr(10), ' ')}", file=sys.stderr)
        return 1
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
