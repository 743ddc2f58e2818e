"""The files the tools write: ROS 2 parameter files and JointTrajectory messages, as YAML.

Numbers are written so that every reader types them right: a double always has a decimal
point or an exponent with one (``0.0``, ``1.5e-05``): rcl's parameter parser would take
``0`` for an integer, and PyYAML (``ros2 topic pub``) takes ``1e-05`` for a string.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np


def yaml_float(x: float, digits: int | None = None) -> str:
    """A double as YAML that parses back as that double (17 significant digits by default)."""
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"cannot write the non-finite number {x}")
    text = repr(x) if digits is None else f"{x:.{digits}g}"
    mantissa, _, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    return mantissa + (f"e{exponent}" if exponent else "")


def _value(value: Any) -> str:
    if isinstance(value, str):
        return json.dumps(value)  # a double-quoted YAML string
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    return yaml_float(value)


def nested(flat: Mapping[str, Any]) -> dict:
    """Flat dotted parameter names as the nested groups of a parameter file."""
    tree: dict = {}
    for name, value in flat.items():
        *groups, leaf = name.split(".")
        node = tree
        for group in groups:
            node = node.setdefault(group, {})
        node[leaf] = value
    return tree


def parameter_file_text(params: Mapping[str, Any], comments: Iterable[str] = ()) -> str:
    """A ROS 2 parameter file giving ``params`` (flat names) to every node (``/**``).

    Doubles stay doubles (see the module's docstring): give floats for double parameters.
    """
    lines = [f"# {line}".rstrip() for line in comments]
    lines += ["/**:", "  ros__parameters:"]

    def emit(tree: Mapping[str, Any], indent: int):
        for key, value in tree.items():
            if isinstance(value, Mapping):
                lines.append(f"{' ' * indent}{key}:")
                emit(value, indent + 2)
            else:
                lines.append(f"{' ' * indent}{key}: {_value(value)}")

    emit(nested(params), 4)
    return "\n".join(lines) + "\n"


def joint_trajectory_text(joint_names, times, Q, QD, QDD, comments: Iterable[str] = ()) -> str:
    """A trajectory_msgs/JointTrajectory as the YAML ``ros2 topic pub`` takes (one point a line)."""
    lines = [f"# {line}".rstrip() for line in comments]
    lines.append(f"joint_names: {_value(list(joint_names))}")
    lines.append("points:")
    for t, q, qd, qdd in zip(times, Q, QD, QDD):
        sec, nanosec = divmod(int(round(float(t) * 1e9)), 10**9)
        fields = [f"{name}: [{', '.join(yaml_float(v, 12) for v in values)}]"
                  for name, values in (("positions", q), ("velocities", qd), ("accelerations", qdd))]
        lines.append(f"- {{{', '.join(fields)}, time_from_start: {{sec: {sec}, nanosec: {nanosec}}}}}")
    return "\n".join(lines) + "\n"


def write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` whole or not at all (a temporary file renamed)."""
    path = Path(path)
    temporary = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        temporary.write_text(text)
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)
    return path
