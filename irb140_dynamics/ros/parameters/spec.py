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

    def descriptor(self) -> ParameterDescriptor:
        unit = f" [{self.unit}]" if self.unit else ""
        descriptor = ParameterDescriptor(description=self.description + unit, read_only=self.read_only)
        if isinstance(self.default, int) and not isinstance(self.default, bool):
            if self.minimum is not None or self.maximum is not None:
                descriptor.integer_range = [
                    IntegerRange(
                        from_value=-(2**63) if self.minimum is None else int(self.minimum),
                        to_value=2**63 - 1 if self.maximum is None else int(self.maximum),
                        step=1,
                    )
                ]
        elif self.minimum is not None or self.maximum is not None:
            descriptor.floating_point_range = [
                FloatingPointRange(
                    from_value=-math.inf if self.minimum is None else self.minimum,
                    to_value=math.inf if self.maximum is None else self.maximum,
                    step=0.0,
                )
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
