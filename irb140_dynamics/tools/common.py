"""What the command-line tools share: the model's arguments and the progress of reading a recording (see
cli.py for the rest)."""

from __future__ import annotations

import argparse
from pathlib import Path

from irb140_dynamics.package_files import default_config_path
from irb140_dynamics.tools.cli import ToolError  # noqa: F401 (the tools import it from here too)


def add_model_arguments(parser: argparse.ArgumentParser, role: str = "the model") -> None:
    """--params-file, --urdf, --base, --tip and -p: the model, read as ``core.io.model_source`` says."""
    group = parser.add_argument_group(role)
    group.add_argument(
        "--params-file",
        metavar="F",
        help="a ROS 2 parameter file: the model's parameters, or "
        "model.source: robot_description with model.urdf_file (default: the package's IRB-140)",
    )
    group.add_argument(
        "--urdf",
        metavar="FILE",
        help="the model from this URDF's chain (the parameter file, if "
        "any, gives gravity, payload.* and the chain's limits, friction, armature)",
    )
    group.add_argument("--base", metavar="LINK", help="the URDF link the chain starts from (default: the root)")
    group.add_argument("--tip", metavar="LINK", help="the URDF link the chain ends at (default: the only leaf)")
    group.add_argument(
        "-p",
        dest="overrides",
        action="append",
        default=[],
        metavar="NAME:=VALUE",
        help="a parameter over the file's (value as YAML), e.g. -p gravity:=[0.0,0.0,-9.81]",
    )


def model_of(args: argparse.Namespace):
    """The model of the arguments that ``add_model_arguments`` declared (ValueError in one line)."""
    from irb140_dynamics.core.io.model_source import parse_override, tool_model

    overrides = dict(parse_override(text) for text in args.overrides)
    return tool_model(args.params_file, args.urdf, args.base, args.tip, overrides, default_config_path())


def reading_progress(tool: str):
    """``progress(path, done, total)``, the identification pipeline's form, for the samples of
    a recording read: 'identify: reading run.mcap: [###   ] 1,234/2,345 samples, 3 s left'
    (see ``progress``)."""
    from irb140_dynamics.tools.progress import Progress

    bars: dict[str, Progress] = {}

    def show(path: str, done: int, total: int) -> None:
        if path not in bars:
            bars[path] = Progress(f"{tool}: reading {Path(path).name}", "samples")
        bars[path](done, total)

    return show
