"""The values given to a node at startup (params files, ``-p``), read through rclpy's public
API, and a warning for each that no node of the package has.

Made with ``NODE_OPTIONS``, rclpy declares every value given as a parameter of the node;
``Overrides`` undeclares them at once and keeps them, for the node's own declarations (with
descriptors) to take. What is left is warned about by name, with the nearest known name: a
typo (``payload.mas``) or a list written as a mapping (``dh: {a: ...}``, flattened by rcl to
``dh.a``) would otherwise leave the default in force without a word. A sibling node's
parameter (one ``/**`` section serves them all) is no typo.
"""

from __future__ import annotations

from typing import Any

from rclpy.node import Node
from rclpy.parameter import Parameter

from irb140_dynamics.core.io.parameter_names import (
    PER_JOINT_SUFFIXES,
    sibling_parameter_names,
    unknown_lines,
    unknown_names,
)
from irb140_dynamics.ros.parameters.spec import Spec, declare

# how every node of the package is made: the values given read as parameters (see above),
# the parameter services the package's own (``services``)
NODE_OPTIONS = {"automatically_declare_parameters_from_overrides": True, "start_parameter_services": False}
RCLPY_PARAMETERS = ("use_sim_time", "start_type_description_service")  # declared by rclpy itself: left to it
MAX_UNKNOWN_WARNINGS = 10


class Overrides:
    """The values given to ``node`` at startup, by name, until its parameters take them."""

    def __init__(self, node: Node):
        if any(service.srv_name.endswith("/set_parameters") for service in node.services):  # rclpy's: no NODE_OPTIONS
            raise TypeError(f"{node.get_name()} was made without NODE_OPTIONS: the values given would be lost")
        self._node = node
        names = [name for name in node.list_parameters([], 0).names if name not in RCLPY_PARAMETERS]
        self.given: dict[str, Parameter] = {name: node.get_parameter(name) for name in names}
        for name in names:
            node.undeclare_parameter(name)

    def declare(self, spec: Spec) -> Any:
        """Declare ``spec``'s parameter with the value given, else its default; its value."""
        return declare(self._node, spec, self.given.pop(spec.name, None))

    def warn_unknown(self, joint_names) -> None:
        """Warn about each value given that no node of the package has (``joint_names``:
        the model's, None while a URDF is awaited), naming the nearest known name
        (``core.io.parameter_names``, as the tools refuse them)."""
        declared = set(self._node.list_parameters([], 0).names)
        known = sibling_parameter_names(joint_names) | declared
        given = [
            name
            for name in self.given
            if not (joint_names is None and name.endswith(PER_JOINT_SUFFIXES))  # a joint of a model still to come
        ]
        lines = unknown_lines(unknown_names(given, known, joint_names), " (ignored)", self._description)
        logger = self._node.get_logger()
        for line in lines[:MAX_UNKNOWN_WARNINGS]:
            logger.warning(line)
        if len(lines) > MAX_UNKNOWN_WARNINGS:
            logger.warning(f"... and {len(lines) - MAX_UNKNOWN_WARNINGS} more unknown parameters")

    def _description(self, name: str) -> str:
        return self._node.describe_parameter(name).description if self._node.has_parameter(name) else ""
