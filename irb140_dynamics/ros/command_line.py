"""A node's command line before ROS starts: ``--help``, and ROS arguments without ``--ros-args``.

A node takes no arguments of its own: everything it reads comes after ``--ros-args``
(``-p NAME:=VALUE``, ``--params-file FILE``, remappings). ``-h``/``--help`` prints the
node's usage, its parameters listed from their Specs (name, type, default, range, unit,
description), and exits 0 without starting ROS. A ROS argument typed before
``--ros-args`` (``id_node -p payload.mass:=2.0``) would be ignored by rcl and leave the
default in force without a word: it is refused, with the line to type instead.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field
from typing import Any, Iterable

ROS_ARGS = "--ros-args"
HELP = ("-h", "--help")
# the flags rcl reads after --ros-args (design.ros2.org "ROS command line arguments")
ROS_FLAGS = ("-p", "--param", "--params-file", "-r", "--remap", "-e", "--enclave", "--log-level",
             "--log-config-file", "--enable-rosout-logs", "--disable-rosout-logs", "--enable-stdout-logs",
             "--disable-stdout-logs", "--enable-external-lib-logs", "--disable-external-lib-logs")


@dataclass
class Usage:
    """What ``--help`` prints for a node: a summary and its parameters by section."""

    name: str
    summary: str
    sections: list[tuple[str, list]] = field(default_factory=list)  # (title, Specs)
    notes: list[str] = field(default_factory=list)

    def text(self) -> str:
        lines = [
            f"usage: {self.name} [-h] [--ros-args [--params-file FILE] [-p NAME:=VALUE] ...]",
            f"       ros2 run irb140_dynamics {self.name} --ros-args -p NAME:=VALUE",
            "",
            *textwrap.wrap(self.summary, 92),
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


def describe_spec(spec) -> list[str]:
    """Two or more lines for one parameter: name (type, default, range), then its description."""
    facts = [type_name(spec.default)]
    default = default_text(spec.default)
    if default is not None:
        facts.append(f"default {default}")
    bounds = range_text(spec)
    if bounds:
        facts.append(bounds)
    if spec.read_only:
        facts.append("read-only: set at startup")
    unit = f" [{spec.unit}]" if spec.unit else ""
    head = f"  {spec.name} ({', '.join(facts)})"
    body = textwrap.wrap(spec.description + unit, 88, initial_indent="      ", subsequent_indent="      ")
    return [head, *body]


def type_name(default: Any) -> str:
    """The ROS parameter type of a Spec's default (a value, or a Parameter.Type)."""
    if hasattr(default, "name") and not isinstance(default, (str, bool, int, float, list, tuple)):
        return {"DOUBLE_ARRAY": "double[]", "INTEGER_ARRAY": "integer[]", "STRING_ARRAY": "string[]",
                "BOOL_ARRAY": "bool[]"}.get(default.name, default.name.lower())
    if isinstance(default, bool):
        return "bool"
    if isinstance(default, int):
        return "integer"
    if isinstance(default, float):
        return "double"
    if isinstance(default, str):
        return "string"
    if isinstance(default, (list, tuple)):
        item = type_name(default[0]) if default else "double"
        return f"{item}[]"
    return type(default).__name__


def default_text(default: Any) -> str | None:
    """The default as a user would write it; None when there is none (a type only)."""
    if hasattr(default, "name") and not isinstance(default, (str, bool, int, float, list, tuple)):
        return None
    if isinstance(default, bool):
        return "true" if default else "false"
    if isinstance(default, str):
        return f"'{default}'"
    if isinstance(default, (list, tuple)):
        return "[" + ", ".join(default_text(x) or "" for x in default) + "]"
    return repr(default)


def range_text(spec) -> str:
    low, high = getattr(spec, "minimum", None), getattr(spec, "maximum", None)
    if low is None and high is None:
        return ""
    unit = f" {spec.unit}" if spec.unit else ""
    low = "-inf" if low is None or math.isinf(low) else f"{low:g}"
    high = "inf" if high is None or math.isinf(high) else f"{high:g}"
    return f"{low} to {high}{unit}"


def own_arguments(argv: Iterable[str]) -> list[str]:
    """The arguments outside every ``--ros-args ... [--]`` span (argv without the program)."""
    own, inside = [], False
    for argument in list(argv)[1:]:
        if argument == ROS_ARGS:
            inside = True
        elif inside and argument == "--":
            inside = False
        elif not inside:
            own.append(argument)
    return own


def refusal(name: str, argv: list[str]) -> str | None:
    """Why the node will not start with these arguments (one line), or None. Help is not
    a refusal (see ``wants_help``)."""
    own = [a for a in own_arguments(argv) if a not in HELP]
    if not own:
        return None
    first = own[0]
    if first in ROS_FLAGS or ":=" in first or first.startswith("__"):
        rest = " ".join(own)
        return (f"{name}: '{rest}' is a ROS argument and would be ignored: add --ros-args before it, "
                f"e.g. {name} --ros-args {rest}")
    return f"{name}: unknown argument '{first}': a node takes only ROS arguments, after --ros-args (see {name} --help)"


def wants_help(argv: list[str]) -> bool:
    return any(a in HELP for a in own_arguments(argv))


def model_sections(per_joint_title: str = "Per joint (NAME.x for each NAME of joint_names)") -> list[tuple[str, list]]:
    """The model's parameters (every node's): source, whole-arm, per joint, URDF source."""
    from ..package_files import default_config_path
    from .model_source import DESCRIPTION_PARAMETERS, SOURCE
    from .params import model_specs

    path = default_config_path()
    defaults = {}
    try:
        from ..core.model import read_parameter_file

        defaults = read_parameter_file(path)
    except Exception:  # noqa: BLE001  (help without the file: no defaults shown)
        pass
    names = list(defaults.get("joint_names", []))
    from .params import Spec

    joint_names = Spec("joint_names", names or ["joint_1"], "the model's joints, base to flange", read_only=True)
    specs = model_specs(["NAME"], {})
    whole = [spec for spec in specs if not spec.name.startswith("NAME.")]
    whole = [_with_default(spec, defaults) for spec in whole]
    per_joint = [spec for spec in specs if spec.name.startswith("NAME.")]
    return [
        ("Model (defaults: the built-in IRB-140 model, config/irb140.yaml)", [SOURCE, joint_names, *whole]),
        (f"{per_joint_title}; the built-in model gives every one of its joints", per_joint),
        ("Model from a URDF (model.source: robot_description)", list(DESCRIPTION_PARAMETERS)),
    ]


def _with_default(spec, defaults: dict):
    from dataclasses import replace

    return replace(spec, default=defaults[spec.name]) if spec.name in defaults else spec
