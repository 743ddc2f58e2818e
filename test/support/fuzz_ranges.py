"""Hostile values for the nodes' numeric parameters, and what a node must answer to each
(test_fuzz_parameter_ranges.py, bench/fuzz_parameters.py)."""

from __future__ import annotations

import math

from rcl_interfaces.msg import ParameterType
from rclpy.parameter import Parameter

from irb140_dynamics.nodes.demo_node.node import DemoNode
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode
from irb140_dynamics.nodes.sim_node.node import SimNode
from irb140_dynamics.nodes.trajectory_check_node.node import TrajectoryCheckNode

NODES = {
    "id_node": IdNode,
    "payload_check_node": PayloadCheckNode,
    "sim_node": SimNode,
    "demo_node": DemoNode,
    "trajectory_check_node": TrajectoryCheckNode,
}
SEED = 23
HOSTILE = (math.inf, -math.inf, math.nan, 1e308, -1e308, -1.0, 0.0, -1, 0, 1, 3, 2**62, 5e-324)


def numeric_parameters(node) -> dict:
    """name -> descriptor of each integer or double parameter of the node."""
    names = node.list_parameters([], 0).names
    described = node.describe_parameters(names)
    return {
        name: d
        for name, d in zip(names, described)
        if d.type in (ParameterType.PARAMETER_INTEGER, ParameterType.PARAMETER_DOUBLE)
    }


def bounds(descriptor) -> tuple[float, float]:
    ranges = descriptor.floating_point_range or descriptor.integer_range
    if not ranges:
        return -math.inf, math.inf
    return ranges[0].from_value, ranges[0].to_value


def candidates(rng, descriptor) -> list:
    """HOSTILE and values in and just outside the parameter's range."""
    low, high = bounds(descriptor)
    span = high - low if math.isfinite(high - low) else 1.0
    inside = low + rng.random() * span
    values = [*HOSTILE, low, high, inside, low - 0.5 * span - 1.0, high + 0.5 * span + 1.0, high * 1e6 + 1]
    if descriptor.type == ParameterType.PARAMETER_INTEGER:
        values += [int(inside), int(low), int(high), int(high) + 1, int(low) - 1]
    else:
        values += [int(inside)]  # an integer for a double: accepted as a float
    return values


def as_parameter(name: str, value) -> Parameter:
    if isinstance(value, int) and not isinstance(value, bool):
        if not -(2**63) <= value < 2**63:
            value = float(value)
        else:
            return Parameter(name, Parameter.Type.INTEGER, value)
    return Parameter(name, Parameter.Type.DOUBLE, float(value))


def try_value(node, name: str, descriptor, value) -> str | None:
    """Set one value the way `ros2 param set` does; None when the node answered as it must,
    else what was wrong."""
    return answer(node, name, descriptor, value)[1]


def answer(node, name: str, descriptor, value) -> tuple[bool, str | None]:
    """(accepted, what was wrong or None) for one value set the way `ros2 param set` does."""
    before = node.get_parameter(name).value
    result = node.set_parameters([as_parameter(name, value)])[0]
    after = node.get_parameter(name).value
    low, high = bounds(descriptor)
    integer = descriptor.type == ParameterType.PARAMETER_INTEGER
    fits_type = isinstance(value, int) or not integer
    inside = fits_type and math.isfinite(value) and low <= value <= high
    if not result.successful:
        if not result.reason:
            return False, f"{name} := {value!r}: refused without a reason"
        if not (before == after or (before != before and after != after)):
            return False, f"{name} := {value!r}: refused, yet the value changed from {before!r} to {after!r}"
        if inside and not descriptor.read_only and "out of range" in result.reason:
            return False, f"{name} := {value!r}: within [{low}, {high}] yet refused as out of range: {result.reason}"
        return False, None
    if descriptor.read_only:
        return True, f"{name} := {value!r}: accepted though read-only"
    if not inside:
        return True, f"{name} := {value!r}: accepted though outside [{low}, {high}] (or not finite)"
    if not (isinstance(after, (int, float)) and math.isfinite(after) and after == value):
        return True, f"{name} := {value!r}: accepted, yet the parameter holds {after!r}"
    return True, None
