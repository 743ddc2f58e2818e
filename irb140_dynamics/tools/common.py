"""What the command-line tools share: the model's arguments and the progress of reading a recording (see
cli.py for the rest)."""

from __future__ import annotations

import argparse
import contextlib
import os
import re
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
    try:
        return tool_model(args.params_file, args.urdf, args.base, args.tip, overrides, default_config_path())
    except ValueError as error:
        raise ValueError(in_option_words(str(error), args.params_file, args.base, args.tip, overrides)) from None


# the core's names of the chain's ends where they name the option: the element of a URDF
# error ("URDF tip_link: ..."), "below base_link 'x'", "(tip_link)"; never a link's name
_CHAIN_END = re.compile(r"URDF (base|tip)_link(?=:)|(?<=below )(base|tip)_link(?= ')|(?<=\()(base|tip)_link(?=\))")


def in_option_words(message: str, params_file=None, base=None, tip=None, overrides=None) -> str:
    """A model error in a tool's words: the URDF chain's ends are its --base and --tip
    options (the core names them base_link and tip_link, as the nodes' model.base_link and
    model.tip_link); model.<end>_link where only the params file (or -p) named that end."""
    named = dict(overrides or {})
    if params_file:
        from irb140_dynamics.core.io.params_file import read_parameter_file

        with contextlib.suppress(OSError, ValueError):
            named = {**read_parameter_file(params_file), **named}
    given = {"base": base, "tip": tip}

    def option(match: re.Match) -> str:
        end = next(group for group in match.groups() if group)
        return f"model.{end}_link" if given[end] is None and named.get(f"model.{end}_link") else f"--{end}"

    return _CHAIN_END.sub(option, message)


def model_inputs(args: argparse.Namespace) -> list[tuple[str, Path]]:
    """The files a tool reads its model from, as (shown, absolute path): --params-file and
    --urdf as given, and the package's default parameter file (no output may replace it)."""
    given = []
    for option in ("params_file", "urdf"):
        value = getattr(args, option, None)
        if value:
            given.append((f"--{option.replace('_', '-')} {value}", Path(os.path.abspath(value))))
    default = default_config_path()
    return [*given, (str(default), Path(os.path.abspath(default)))]


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
