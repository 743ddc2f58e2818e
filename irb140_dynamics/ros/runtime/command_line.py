"""A node's command line before ROS starts: ``--help``, and ROS arguments without ``--ros-args``.

A node takes no arguments of its own: everything it reads comes after ``--ros-args``
(``-p NAME:=VALUE``, ``--params-file FILE``, remappings). ``-h``/``--help`` prints the
node's usage, its parameters listed from their descriptors (name, type, default, range,
unit, description), and exits 0 without starting ROS. A ROS argument typed before
``--ros-args`` (``id_node -p payload.mass:=2.0``) would be ignored by rcl and leave the
default in force without a word: it is refused, with the line to type instead.
"""

from __future__ import annotations

import textwrap
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor

from irb140_dynamics.core.io.text_files import InputFileError, read_text_file
from irb140_dynamics.ros.parameters.spec import TYPE_NAMES, Spec

ROS_ARGS = "--ros-args"
HELP = ("-h", "--help")
# the flags rcl reads after --ros-args (design.ros2.org "ROS command line arguments")
ROS_FLAGS = (
    "-p",
    "--param",
    "--params-file",
    "-r",
    "--remap",
    "-e",
    "--enclave",
    "--log-level",
    "--log-config-file",
    "--enable-rosout-logs",
    "--disable-rosout-logs",
    "--enable-stdout-logs",
    "--disable-stdout-logs",
    "--enable-external-lib-logs",
    "--disable-external-lib-logs",
)


@dataclass
class Usage:
    """What ``--help`` prints for a node: a summary and its parameters by section."""

    name: str
    summary: str
    sections: list[tuple[str, list[Spec]]] = field(default_factory=list)  # (title, Specs)
    notes: list[str] = field(default_factory=list)

    def text(self) -> str:
        lines = [
            f"usage: {self.name} [-h] [--ros-args [--params-file FILE] [-p NAME:=VALUE] ...]",
            f"       ros2 run irb140_dynamics {self.name} --ros-args -p NAME:=VALUE",
            "",
            self.summary.strip(),
            "",
            "Parameters are given after --ros-args: -p NAME:=VALUE, or --params-file FILE (YAML, as",
            "config/irb140.yaml); most can be changed while running (ros2 param set), each change",
            "validated whole, a bad value refused with its reason.",
        ]
        for note in self.notes:
            lines += ["", *textwrap.wrap(note, 92)]
        for title, specs in self.sections:
            lines += ["", f"{title}:"]
            for spec in specs:
                lines += describe_spec(spec)
        return "\n".join(lines) + "\n"


def describe_spec(spec: Spec) -> list[str]:
    """Two or more lines for one parameter, from its descriptor: name (type, default, range,
    unit, read-only), then its description."""
    descriptor = spec.descriptor()
    unit = f" {spec.unit}" if spec.unit else ""
    facts = [TYPE_NAMES[spec.type]]
    if spec.has_default:
        facts.append(f"default {default_text(spec.default)}{unit}")
    bounds = range_text(descriptor)
    if bounds:
        facts.append(f"{bounds}{unit}")
    elif unit and not spec.has_default:
        facts.append(unit.strip())
    if descriptor.read_only:
        facts.append("read-only: set at startup")
    body = textwrap.wrap(spec.description, 88, initial_indent="      ", subsequent_indent="      ")
    return [f"  {spec.name} ({', '.join(facts)})", *body]


def default_text(default: Any) -> str:
    """A default as a user would write it."""
    if isinstance(default, bool):
        return "true" if default else "false"
    if isinstance(default, str):
        return f"'{default}'"
    if isinstance(default, (list, tuple)):
        return "[" + ", ".join(default_text(x) for x in default) + "]"
    return repr(default)


def range_text(descriptor: ParameterDescriptor) -> str:
    ranges = descriptor.floating_point_range or descriptor.integer_range
    if not ranges:
        return ""
    return f"{ranges[0].from_value:g} to {ranges[0].to_value:g}"


def split_arguments(argv: Iterable[str]) -> tuple[list[str], list[str]]:
    """(the arguments outside every ``--ros-args ... [--]`` span, those inside), argv without
    the program."""
    own, ros, inside = [], [], False
    for argument in list(argv)[1:]:
        if argument == ROS_ARGS or (inside and argument == "--"):
            inside = argument == ROS_ARGS
        else:
            (ros if inside else own).append(argument)
    return own, ros


def refusal(name: str, argv: list[str]) -> str | None:
    """Why the node will not start with these arguments (one line), or None. Help is not
    a refusal (see ``wants_help``)."""
    own = [a for a in split_arguments(argv)[0] if a not in HELP]
    if not own:
        return None
    first = own[0]
    if first in ROS_FLAGS or ":=" in first or first.startswith("__"):
        rest = " ".join(own)
        return (
            f"cannot start: '{rest}' is a ROS argument and would be ignored: add --ros-args before it, "
            f"e.g. {name} --ros-args {rest}"
        )
    return f"cannot start: unknown argument '{first}': {name} takes only ROS arguments, after --ros-args (see --help)"


def wants_help(argv: list[str]) -> bool:
    return any(a in HELP for a in split_arguments(argv)[0])


_given: list[str] = []  # the params files of the node's command line (set by ``before_start``)


def params_files(argv: list[str]) -> list[str]:
    """The files of every ``--params-file`` inside ``--ros-args``, in order."""
    ros = split_arguments(argv)[1]
    return [path for flag, path in zip(ros, ros[1:]) if flag == "--params-file"]


def params_files_given() -> list[str]:
    """The params files the running node was started with (empty in-process)."""
    return list(_given)


def params_file_problem(path: str) -> str | None:
    """Why rcl should not be given this params file (one line naming it), or None: missing,
    not a regular file (a device, /dev/zero), too large, not text (core.io.text_files)."""
    try:
        read_text_file(path, "params file")
    except InputFileError as error:
        where = f" (relative paths are read from {Path.cwd()})" if not Path(path).is_absolute() else ""
        return f"{error}{where}"
    return None


def before_start(name: str, argv: list[str], usage) -> tuple[int, str] | None:
    """What to do before ROS starts: (exit code, text to print) for --help (0, the usage),
    a ROS argument outside --ros-args (2) or a params file rcl should not read (1, the
    reason); None to start. ``usage()``: the node's Usage; None for a tool that parses its
    own arguments (then only the params files are checked)."""
    if usage is not None:
        if wants_help(argv):
            return 0, usage().text()
        refused = refusal(name, argv)
        if refused:
            return 2, refused
    files = params_files(argv)
    for path in files:
        problem = params_file_problem(path)
        if problem:
            return 1, f"cannot start: {problem}"
    _given[:] = files
    return None
