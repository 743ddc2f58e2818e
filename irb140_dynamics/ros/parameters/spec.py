"""One parameter of a node (``Spec``): its name, default, type, range, unit, read-only flag
and description, stated once: for rclpy to enforce (its ``ParameterDescriptor``), for
``ros2 param describe`` and for ``--help``; and its declaration with the value given."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.node import Node
from rclpy.parameter import Parameter

TYPE_NAMES = {kind: kind.name.lower().replace("_array", "[]") for kind in Parameter.Type}  # as --help says them


@dataclass(frozen=True)
class Spec:
    """One parameter: its name, default (or its type when it has none) and descriptor text."""

    name: str
    default: Any
    description: str
    unit: str = ""
    read_only: bool = False
    minimum: float | None = None  # for double and integer parameters
    maximum: float | None = None

    @property
    def type(self) -> Parameter.Type:
        return self.default if not self.has_default else Parameter.Type.from_parameter_value(self.default)

    @property
    def type_name(self) -> str:
        return TYPE_NAMES[self.type]

    @property
    def has_default(self) -> bool:
        return not isinstance(self.default, Parameter.Type)

    def descriptor(self) -> ParameterDescriptor:
        """The descriptor, with the range; a numeric parameter must have a finite one (no
        inf, nan or 1e308 gets past rclpy's range check then)."""
        unit = f" [{self.unit}]" if self.unit else ""
        descriptor = ParameterDescriptor(
            name=self.name, type=self.type.value, description=self.description + unit, read_only=self.read_only
        )
        low, high = self.minimum, self.maximum
        if self.type in (Parameter.Type.INTEGER, Parameter.Type.DOUBLE) and not (
            low is not None and high is not None and math.isfinite(high - low)
        ):
            raise ValueError(f"{self.name}: a numeric parameter needs a finite range (minimum and maximum)")
        if self.type == Parameter.Type.INTEGER:
            descriptor.integer_range = [IntegerRange(from_value=int(low), to_value=int(high), step=1)]
        elif self.type == Parameter.Type.DOUBLE:
            descriptor.floating_point_range = [
                FloatingPointRange(from_value=float(low), to_value=float(high), step=0.0)
            ]
        return descriptor


def as_type(parameter: Parameter, wanted: Parameter.Type) -> Parameter:
    """An integer given for a double parameter (``-p payload.mass:=2``, a params file's
    ``mass: 2``, ``ros2 param set ... payload.mass 3``) as that double; else unchanged."""
    if wanted == Parameter.Type.DOUBLE and parameter.type_ == Parameter.Type.INTEGER:
        return Parameter(parameter.name, Parameter.Type.DOUBLE, float(parameter.value))
    if wanted == Parameter.Type.DOUBLE_ARRAY and parameter.type_ == Parameter.Type.INTEGER_ARRAY:
        return Parameter(parameter.name, Parameter.Type.DOUBLE_ARRAY, [float(x) for x in parameter.value])
    return parameter


def declare(node: Node, spec: Spec, given: Parameter | None = None) -> Any:
    """Declare the parameter of ``spec`` with the value ``given`` at startup (None: its
    default); its value, or a ValueError in one line naming it when rclpy refuses the value."""
    descriptor = spec.descriptor()
    if given is None:
        value = spec.default
    else:
        given = as_type(given, spec.type)
        if given.type_ != spec.type:
            raise ValueError(f"{spec.name}: expected a value of type {TYPE_NAMES[spec.type]}")
        value = given.value
    try:
        return node.declare_parameter(spec.name, value, descriptor, ignore_override=True).value
    except InvalidParameterTypeException:
        raise ValueError(f"{spec.name}: expected a value of type {TYPE_NAMES[spec.type]}") from None
    except InvalidParameterValueException as error:
        if given is None or spec.minimum is None:
            raise ValueError(f"{spec.name}: {error}") from None
        raise ValueError(f"{spec.name}: must be between {spec.minimum:g} and {spec.maximum:g}, got {value}") from None
