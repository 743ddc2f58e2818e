"""Parameters given to a node that no node of this package has: warned about by name.

A typo in a params file (``payload.mas``) or on the command line, or a list parameter
written as a mapping (``dh: {a: ..., alpha: ...}``, which rcl flattens to ``dh.a``, ...),
would otherwise leave the default in force without a word. A parameter of a sibling node
(one ``/**`` section serves them all) is not warned about.
"""

from __future__ import annotations

import difflib

from rclpy.node import Node

from irb140_dynamics.ros.parameters.catalog import PER_JOINT_SUFFIXES, sibling_parameter_names

MAX_UNKNOWN_WARNINGS = 10


def warn_unknown_overrides(node: Node) -> None:
    """Warn about each parameter given to the node (params file, -p) that no node of this
    package declares, with the nearest known name."""
    declared = set(node.list_parameters([], 0).names)
    unknown = sorted(name for name in node._parameter_overrides if name not in declared)
    if not unknown:
        return
    joint_names = node.get_parameter("joint_names").value if node.has_parameter("joint_names") else None
    known, per_joint_suffixes = sibling_parameter_names(joint_names), PER_JOINT_SUFFIXES
    known |= declared
    lines, by_parent = [], {}
    for name in unknown:
        if name in known or (joint_names is None and name.endswith(per_joint_suffixes)):
            continue  # a sibling's, or a per-joint one of a model still to come (a URDF topic)
        parent = _known_parent(name, declared)
        if parent is not None:
            by_parent.setdefault(parent, []).append(name)
            continue
        nearest = difflib.get_close_matches(name, sorted(known), n=1, cutoff=0.6)
        hint = f"; did you mean {nearest[0]}?" if nearest else ""
        lines.append(f"unknown parameter {name} (ignored){hint}")
    for parent, names in by_parent.items():
        what = node.describe_parameter(parent).description
        lines.append(
            f"unknown parameter{'s' if len(names) > 1 else ''} {', '.join(names)} (ignored): "
            f"{parent} is one parameter, not a mapping: {what}"
        )
    for line in lines[:MAX_UNKNOWN_WARNINGS]:
        node.get_logger().warning(line)
    if len(lines) > MAX_UNKNOWN_WARNINGS:
        node.get_logger().warning(f"... and {len(lines) - MAX_UNKNOWN_WARNINGS} more unknown parameters")


def _known_parent(name: str, declared: set[str]) -> str | None:
    """The declared parameter ``name`` lies under (``joint_1.dh`` for ``joint_1.dh.a``), if any."""
    parent = name
    while "." in parent:
        parent = parent.rsplit(".", 1)[0]
        if parent in declared:
            return parent
    return None
