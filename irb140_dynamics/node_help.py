"""What a node's ``--help`` prints: its usage, summary, notes and parameters by section, each
parameter from its Spec (ros.parameters.spec: name, type, default, range, unit, read-only
flag, description). Text only: imports nothing of the package, starts nothing."""

from __future__ import annotations

import textwrap
from dataclasses import dataclass, field
from typing import Any


@dataclass
class Usage:
    """What ``--help`` prints for a node: a summary, notes and its parameters by section."""

    name: str
    summary: str
    sections: list[tuple[str, list]] = field(default_factory=list)  # (title, Specs)
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


def describe_spec(spec) -> list[str]:
    """``name (type, default, range, unit, read-only)`` and the description below it."""
    unit = f" {spec.unit}" if spec.unit else ""
    facts = [spec.type_name]
    if spec.has_default:
        facts.append(f"default {default_text(spec.default)}{unit}")
    if spec.minimum is not None and spec.maximum is not None:
        facts.append(f"{spec.minimum:g} to {spec.maximum:g}{unit}")
    elif unit and not spec.has_default:
        facts.append(spec.unit)
    if spec.read_only:
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
