"""Parameters given to a node that no node of this package has: warned about by name.

A typo in a params file (``payload.mas``) or on the command line, or a list parameter
written as a mapping (``dh: {a: ..., alpha: ...}``, which rcl flattens to ``dh.a``, ...),
would otherwise leave the default in force without a word.
"""

from __future__ import annotations

import difflib

from rclpy.node import Node

MAX_UNKNOWN_WARNINGS = 10


def warn_unknown_overrides(node: Node) -> None:
    """Warn about each parameter given to the node (params file, -p) that no node of this
    package declares, with the nearest known name: a typo would silently leave a default."""
    from .node_parameters import PACKAGE_PARAMETERS  # here: it imports params, which imports this

    known = set(node.list_parameters([], 0).names) | PACKAGE_PARAMETERS
    unknown = sorted(name for name in node._parameter_overrides if name not in known)
    by_parent: dict[str, list[str]] = {}
    lines = []
    for name in unknown:
        parent = name.rsplit(".", 1)[0]
        while "." in parent and parent not in known:
            parent = parent.rsplit(".", 1)[0]
        if parent in known and node.has_parameter(parent):
            by_parent.setdefault(parent, []).append(name)
            continue
        nearest = difflib.get_close_matches(name, sorted(known), n=1, cutoff=0.6)
        hint = f"; did you mean {nearest[0]}?" if nearest else ""
        lines.append(f"unknown parameter {name} (ignored){hint}")
    for parent, names in by_parent.items():
        what = node.describe_parameter(parent).description
        lines.append(f"unknown parameter{'s' if len(names) > 1 else ''} {', '.join(names)} (ignored): "
                     f"{parent} is one parameter, not a mapping: {what}")
    for line in lines[:MAX_UNKNOWN_WARNINGS]:
        node.get_logger().warning(line)
    if len(lines) > MAX_UNKNOWN_WARNINGS:
        node.get_logger().warning(f"... and {len(lines) - MAX_UNKNOWN_WARNINGS} more unknown parameters")
