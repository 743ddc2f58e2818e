"""One parameter of a node (``Spec``: name, default, descriptor with its range) and its
declaration, a value rclpy refuses made a ValueError naming the parameter."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.node import Node
from rclpy.parameter import Parameter


@dataclass(frozen=True)
class Spec:
    """One parameter: its name, default (or type when it has none) and descriptor text."""

    name: str
    default: Any
    description: str
    unit: str = ""
    read_only: bool = False
    minimum: float | None = None  # for double and integer parameters
    maximum: float | None = None

    @property
    def numeric(self) -> bool:
        """An integer or double parameter (not bool, not an array)."""
        kind = self.default
        if isinstance(kind, Parameter.Type):
            return kind in (Parameter.Type.INTEGER, Parameter.Type.DOUBLE)
        return isinstance(kind, (int, float)) and not isinstance(kind, bool)

    def descriptor(self) -> ParameterDescriptor:
        """The descriptor, with the range; a numeric parameter must have a finite one (no
        inf, nan or 1e308 gets past rclpy's range check then)."""
        unit = f" [{self.unit}]" if self.unit else ""
        descriptor = ParameterDescriptor(description=self.description + unit, read_only=self.read_only)
        if not self.numeric:
            return descriptor
        if self.minimum is None or self.maximum is None or not math.isfinite(self.maximum - self.minimum):
            raise ValueError(f"{self.name}: a numeric parameter needs a finite range (minimum and maximum)")
        if self.default == Parameter.Type.INTEGER or isinstance(self.default, int):
            descriptor.integer_range = [IntegerRange(from_value=int(self.minimum), to_value=int(self.maximum), step=1)]
        else:
            descriptor.floating_point_range = [
                FloatingPointRange(from_value=float(self.minimum), to_value=float(self.maximum), step=0.0)
            ]
        return descriptor


def _range_text(spec: Spec) -> str:
    if spec.minimum is not None and spec.maximum is not None:
        return f"must be between {spec.minimum:g} and {spec.maximum:g}"
    if spec.minimum is not None:
        return f"must be >= {spec.minimum:g}"
    return f"must be <= {spec.maximum:g}"


def declare(node: Node, spec) -> Any:
    """Declare a parameter of a Spec; a value rclpy refuses is a ValueError naming it."""
    _as_double(node, spec)
    try:
        return node.declare_parameter(spec.name, spec.default, spec.descriptor()).value
    except InvalidParameterTypeException:
        kind = spec.default
        if not isinstance(kind, Parameter.Type):
            kind = Parameter.Type.from_parameter_value(kind)
        hint = "; write doubles with a decimal point, e.g. 2.0" if "DOUBLE" in kind.name else ""
        raise ValueError(f"{spec.name}: expected a value of type {kind.name.lower()}{hint}") from None
    except InvalidParameterValueException as error:
        given = node._parameter_overrides.get(spec.name)  # the value rclpy refused (its range)
        if given is None or (spec.minimum is None and spec.maximum is None):
            raise ValueError(f"{spec.name}: {error}") from None
        raise ValueError(f"{spec.name}: {_range_text(spec)}, got {given.value}") from None


def _as_double(node: Node, spec) -> None:
    """An integer given for a double parameter (``-p payload.mass:=2``, a params file's
    ``mass: 2``) is taken as that double, as ``ros2 param set`` users expect."""
    given = node._parameter_overrides.get(spec.name)
    if given is None:
        return
    kind = spec.default if isinstance(spec.default, Parameter.Type) else None
    if kind is None and not isinstance(spec.default, bool):
        if isinstance(spec.default, float):
            kind = Parameter.Type.DOUBLE
        elif isinstance(spec.default, list) and spec.default and all(isinstance(x, float) for x in spec.default):
            kind = Parameter.Type.DOUBLE_ARRAY
    if kind == Parameter.Type.DOUBLE and given.type_ == Parameter.Type.INTEGER:
        node._parameter_overrides[spec.name] = Parameter(spec.name, Parameter.Type.DOUBLE, float(given.value))
    elif kind == Parameter.Type.DOUBLE_ARRAY and given.type_ == Parameter.Type.INTEGER_ARRAY:
        node._parameter_overrides[spec.name] = Parameter(
            spec.name, Parameter.Type.DOUBLE_ARRAY, [float(x) for x in given.value]
        )
