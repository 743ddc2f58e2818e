"""What the command-line tools share: the arm's arguments and the progress of reading a recording (see
cli.py for the rest)."""

from __future__ import annotations

import argparse
import contextlib
import os
import re
from dataclasses import replace
from pathlib import Path
from typing import Any

from irb140_dynamics.core.errors import one_line
from irb140_dynamics.package_files import default_config_path
from irb140_dynamics.tools.cli import BadArgument, ToolError, shown


def add_model_arguments(parser: argparse.ArgumentParser, role: str = "the model") -> None:
    """--params-file, --urdf, --base, --tip, --hold and -p: the arm, read as ``core.io.arm_source`` says."""
    group = parser.add_argument_group(role)
    group.add_argument(
        "--params-file",
        metavar="F",
        help="a ROS 2 parameter file: the model's parameters over the package's IRB-140, or "
        "model.source: robot_description with model.urdf_file (default: the package's IRB-140)",
    )
    group.add_argument(
        "--urdf",
        metavar="FILE",
        help="the model from this URDF: its chain to --tip, else every moving joint below --base (a chain or a "
        "whole tree; the parameter file, if any, gives gravity in the root link's frame, payload.* and the joints' "
        "limits, friction, armature)",
    )
    group.add_argument(
        "--base",
        "--base-link",
        dest="base",
        metavar="LINK",
        help="the URDF link the chain starts from (default: the root)",
    )
    group.add_argument(
        "--tip",
        "--tip-link",
        dest="tip",
        metavar="LINK",
        help="the URDF link the chain ends at (default: none, the whole tree below --base)",
    )
    group.add_argument(
        "--hold",
        action="append",
        default=[],
        metavar="JOINT=VALUE",
        help="a URDF joint the model leaves out (the rest of the tree with --tip, one above --base) held at VALUE "
        "[rad, m] (repeatable; over model.held_positions; default: zero, or its limit nearest zero where zero is "
        "outside its range; a mimic joint follows its joint)",
    )
    group.add_argument(
        "-p",
        dest="overrides",
        action="append",
        default=[],
        metavar="NAME:=VALUE",
        help="a parameter over the file's (value as YAML), e.g. -p gravity:=[0.0,0.0,-9.81]",
    )


def arm_of(args: argparse.Namespace, chain_for: str | None = None):
    """The arm (``core.io.arm_source.Arm``) of the arguments ``add_model_arguments`` declared:
    ToolError in one line for a bad file or value; BadArgument (exit status 2) for a name no
    executable of the package knows, with the nearest known one. ``chain_for``: what needs a
    serial chain (the payload analysis): ToolError naming --tip for a tree or mimic joints."""
    from irb140_dynamics.core.io.arm_source import HeldPositionError, given_values, read_arm, read_urdf_file
    from irb140_dynamics.core.io.parameter_names import known_parameter_names, unknown_names
    from irb140_dynamics.core.io.params_file import read_parameter_file

    params_file = getattr(args, "params_file", None)
    overrides: list[tuple[str, Any]] = []  # (a -p that is no NAME:=VALUE: refused below, none named)
    try:
        overrides = [parse_override(text) for text in getattr(args, "overrides", None) or []]
        values = given_values([params_file] if params_file else [], overrides)
        urdf = read_urdf_file(args.urdf) if getattr(args, "urdf", None) else None
        arm = read_arm(
            values,
            read_parameter_file(default_config_path()),
            urdf,
            getattr(args, "base", None),
            getattr(args, "tip", None),
            origin=params_file,
            relative_to=Path(params_file).parent if params_file else None,
            hold=getattr(args, "hold", None) or (),
        )
    except HeldPositionError as error:  # a bad argument: exit status 2
        raise BadArgument(in_option_words(one_line(error))) from None
    except ValueError as error:
        raise ToolError(in_option_words(one_line(error), params_file, args.base, args.tip, dict(overrides))) from None
    known = known_parameter_names(arm.model.joint_names, from_urdf=arm.urdf is not None)
    unknown = unknown_names(values, known, arm.model.joint_names)
    if unknown:
        raise BadArgument(_unknown_text(unknown, dict(overrides), params_file))
    if arm.urdf is None and not params_file:  # the package's own arm: named by its file
        arm = replace(arm, origin=str(default_config_path()))
    if chain_for and not arm.model.is_chain:
        raise ToolError(_chain_refusal(chain_for, arm))
    return replace(arm, given=values)


def _chain_refusal(chain_for: str, arm) -> str:
    """Why ``arm`` is no serial chain for ``chain_for``, and what to give: a --tip for a tree;
    for a chain with mimic joints (in it, or following it off it: a gripper's other finger),
    a --tip above the joint they follow, that joint held."""
    from irb140_dynamics.core.io.arm_source import is_one_chain

    model = arm.model
    if not is_one_chain(model) or model.mimics is None:
        return (
            f"{chain_for} takes one serial chain, but {shown(arm.origin)} gives {len(model.joints)} joints as a tree "
            "or with mimic joints: give --tip LINK, the end effector's URDF link (the rest of the tree held at zero, "
            "or at --hold JOINT=VALUE)"
        )
    name, leader = next((j.name, m.joint) for j, m in zip(model.joints, model.mimics) if m is not None)
    return _mimic_refusal(chain_for, name, leader)


def _mimic_refusal(chain_for: str, name: str, leader: str) -> str:
    """'X' follows 'Y': end above Y and hold it, the advice whole in the error line: the
    names cut to the room left by the --hold hint (which names Y whole)."""
    from irb140_dynamics.core.errors import LINE_LIMIT
    from irb140_dynamics.core.io.urdf.tree import clipped

    def text(follower: str, followed: str) -> str:
        return (
            f"{chain_for} takes a chain without mimic joints: {follower} follows {followed}; end the chain above "
            f"{followed} (--tip LINK) and hold it (--hold {leader}=VALUE)"
        )

    room = LINE_LIMIT - len(f"{chain_for.split()[0]}: error: ") - len(text("", ""))
    each = max(12, room // 3)
    return text(clipped(repr(name), each), clipped(repr(leader), each))


def _unknown_text(unknown, overrides: dict, params_file) -> str:
    """'unknown parameters in arm.yaml: payload.masss (did you mean payload.mass?); -p:
    joint_6.torque_limt (did you mean joint_6.torque_limit?)'."""
    by_source: dict[str, list[str]] = {}
    for entry in unknown:
        source = "-p" if entry.name in overrides else f"in {shown(params_file)}"
        by_source.setdefault(source, []).append(f"{entry.name} ({entry.why()})")
    plural = "s" if len(unknown) > 1 else ""
    return f"unknown parameter{plural} " + "; ".join(
        f"{source}: {', '.join(names)}" for source, names in by_source.items()
    )


def parse_override(text: str) -> tuple[str, Any]:
    """``name:=value`` (value as YAML, as ``ros2 run ... -p`` reads it) -> (name, value)."""
    import yaml

    name, separator, value = text.partition(":=")
    if not separator or not name.strip():
        raise ValueError(f"-p {text}: expected NAME:=VALUE")
    try:
        return name.strip(), yaml.safe_load(value)
    except yaml.YAMLError as error:
        raise ValueError(f"-p {text}: the value is not YAML ({str(error).splitlines()[0]})") from None


# the core's names of the chain's ends where they name the option: the element of a URDF
# error ("URDF tip_link: ..."), "below base_link 'x'", "(tip_link)"; never a link's name
_CHAIN_END = re.compile(r"URDF (base|tip)_link(?=:)|(?<=below )(base|tip)_link(?= ')|(?<=\()(base|tip)_link(?=\))")


def in_option_words(message: str, params_file=None, base=None, tip=None, overrides=None) -> str:
    """A model error in a tool's words: the URDF chain's ends are its --base and --tip
    options (the core names them base_link and tip_link, as the nodes' model.base_link and
    model.tip_link); model.<end>_link where only the params file (or -p) named that end. A
    URDF wanted is --urdf (the core names the nodes' model.urdf_file)."""
    named = dict(overrides or {})
    if params_file:
        from irb140_dynamics.core.io.params_file import read_parameter_file

        with contextlib.suppress(OSError, ValueError):
            named = {**read_parameter_file(params_file), **named}
    given = {"base": base, "tip": tip}

    def option(match: re.Match) -> str:
        end = next(group for group in match.groups() if group)
        return f"model.{end}_link" if given[end] is None and named.get(f"model.{end}_link") else f"--{end}"

    from irb140_dynamics.core.io.arm_source import GIVE_A_URDF

    return _CHAIN_END.sub(option, message).replace(GIVE_A_URDF, "give --urdf, or model.source: robot_description")


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
