"""Parameters of the nodes: declared with descriptors, validated whole, swapped atomically.

A node lists its parameters as ``Spec``s and gives a ``build`` function that turns all of
their values into the configuration it runs on (a RobotModel, options), raising ValueError
naming the parameter when something is wrong. Everything that can fail, and everything
slow (compiling kernels), belongs in ``build``: a configuration that was built is used
(``build`` may return None while an input from elsewhere, a URDF, has yet to come).
``LiveParameters`` declares them, builds the
first configuration (a failure stops startup), and from then on checks every change by
building the whole new configuration before it is accepted: a refused change keeps the old
configuration, an accepted one replaces it in a single assignment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy

from ..core.model import check_joint_names, read_parameter_file
from ..package_files import CONFIG_NAME, PACKAGE, default_config_path  # noqa: F401 (PACKAGE, CONFIG_NAME: re-exported)



@dataclass(frozen=True)
class Spec:
    """One parameter: its name, default (or type when it has none) and descriptor text."""

    name: str
    default: Any
    description: str
    unit: str = ""
    read_only: bool = False
    minimum: float | None = None  # for double parameters
    maximum: float | None = None

    def descriptor(self) -> ParameterDescriptor:
        unit = f" [{self.unit}]" if self.unit else ""
        descriptor = ParameterDescriptor(description=self.description + unit, read_only=self.read_only)
        if self.minimum is not None or self.maximum is not None:
            descriptor.floating_point_range = [
                FloatingPointRange(
                    from_value=-math.inf if self.minimum is None else self.minimum,
                    to_value=math.inf if self.maximum is None else self.maximum,
                    step=0.0,
                )
            ]
        return descriptor


RELIABILITIES = {"best_effort": ReliabilityPolicy.BEST_EFFORT, "reliable": ReliabilityPolicy.RELIABLE}
QOS_PARAMETERS = [
    Spec("qos.reliability", "best_effort",
         "joint_states subscription reliability: 'best_effort' (takes reliable and best-effort publishers) "
         "or 'reliable'", read_only=True),
    Spec("qos.depth", 10, "queue depth of joint_states, ~/reference and the torque topics", read_only=True),
]


def check_choice(name: str, value, choices) -> None:
    if value not in choices:
        raise ValueError(f"{name}: must be one of {', '.join(choices)}; got {value!r}")


def check_qos(values: dict) -> None:
    check_choice("qos.reliability", values["qos.reliability"], RELIABILITIES)
    if values["qos.depth"] < 1:
        raise ValueError(f"qos.depth: must be >= 1, got {values['qos.depth']}")


def joint_states_qos(node: Node) -> QoSProfile:
    """The joint_states subscription's QoS from the node's qos.* parameters."""
    reliability = RELIABILITIES[node.get_parameter("qos.reliability").value]
    return QoSProfile(depth=node.get_parameter("qos.depth").value, reliability=reliability)


def model_specs(joint_names: list[str], defaults: dict[str, Any]) -> list[Spec]:
    """The model's parameters for these joints; defaults from the default model's file.

    The per-joint defaults apply only when the joints are the default model's own: a
    params file naming other joints must give every value (nothing is silently borrowed).
    """
    own = list(defaults.get("joint_names", [])) == list(joint_names)

    def default(name, kind):
        return defaults[name] if own and name in defaults else kind

    specs = [
        Spec("gravity", defaults.get("gravity", [0.0, 0.0, -9.81]), "gravity in the base frame", "m/s^2"),
        Spec("friction.smoothing_velocity", defaults.get("friction.smoothing_velocity", 0.01),
             "Coulomb friction is coulomb * tanh(qd / this)", "rad/s", minimum=1e-9),
        *_body_specs("payload", "the payload on the flange", "flange frame", lambda name, kind: defaults.get(name, kind)),
    ]
    for joint in joint_names:
        specs += [
            Spec(f"{joint}.dh", default(f"{joint}.dh", Parameter.Type.DOUBLE_ARRAY),
                 "standard DH row [a, alpha, d, theta_offset]", "m, rad, m, rad"),
            *_body_specs(f"{joint}.link", f"the link {joint} moves", "its DH frame", default),
            Spec(f"{joint}.position_limits", default(f"{joint}.position_limits", [-math.pi, math.pi]),
                 "[lower, upper] joint position", "rad"),
            Spec(f"{joint}.torque_limit", default(f"{joint}.torque_limit", 0.0),
                 "joint torque limit, 0 = none given", "N m", minimum=0.0),
            Spec(f"{joint}.velocity_limit", default(f"{joint}.velocity_limit", 0.0),
                 "joint speed limit, 0 = none given", "rad/s", minimum=0.0),
            Spec(f"{joint}.acceleration_limit", default(f"{joint}.acceleration_limit", 0.0),
                 "joint acceleration limit, 0 = none given", "rad/s^2", minimum=0.0),
            Spec(f"{joint}.friction.viscous", default(f"{joint}.friction.viscous", 0.0),
                 "viscous friction coefficient", "N m s/rad", minimum=0.0),
            Spec(f"{joint}.friction.coulomb", default(f"{joint}.friction.coulomb", 0.0),
                 "Coulomb friction level (smoothed, see friction.smoothing_velocity)", "N m", minimum=0.0),
            Spec(f"{joint}.armature", default(f"{joint}.armature", 0.0),
                 "rotor inertia reflected through the gear, added to M's diagonal", "kg m^2", minimum=0.0),
        ]
    return specs


def _body_specs(prefix: str, what: str, frame: str, default) -> list[Spec]:
    zeros3, zeros6 = [0.0] * 3, [0.0] * 6
    optional = prefix == "payload"
    return [
        Spec(f"{prefix}.mass", default(f"{prefix}.mass", 0.0 if optional else Parameter.Type.DOUBLE),
             f"mass of {what}", "kg", minimum=0.0),
        Spec(f"{prefix}.com", default(f"{prefix}.com", zeros3 if optional else Parameter.Type.DOUBLE_ARRAY),
             f"centre of mass of {what}, in {frame}", "m"),
        Spec(f"{prefix}.inertia", default(f"{prefix}.inertia", zeros6 if optional else Parameter.Type.DOUBLE_ARRAY),
             f"inertia of {what} about its centre of mass, [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]", "kg m^2"),
    ]


def declare_model(
    node: Node, extra: list[Spec], build: Callable[[dict], Any], per_joint: Callable[[list[str]], list[Spec]] = None
) -> "LiveParameters":
    """Declare the robot model's parameters and a node's own (``extra``, and ``per_joint``
    specs made for the model's joint names), with the default model's defaults."""
    path = default_config_path()
    if not path.is_file():
        raise ValueError(f"default model: no {path}; is the package installed? (or give --params-file)")
    defaults = read_parameter_file(path)
    node.get_logger().info(f"default model: {path}")
    names = _declare(
        node,
        Spec("joint_names", defaults["joint_names"], "the model's joints, base to flange", read_only=True),
    )
    names = check_joint_names(names)  # they become parameter prefixes: check them first
    own = per_joint(names) if per_joint else []
    return LiveParameters(node, [*model_specs(names, defaults), *extra, *own], build, ["joint_names"])


class LiveParameters:
    """The node's validated configuration, kept in step with its parameters."""

    def __init__(self, node: Node, specs: list[Spec], build: Callable[[dict], Any], declared=()):
        """``declared``: names of parameters the caller has declared already."""
        self._node, self._build = node, build
        self._names = [spec.name for spec in specs] + list(declared)
        for spec in specs:
            _declare(node, spec)
        self.current = build(self.values())
        self._pending = None  # (values, configuration) checked, not yet applied
        self._listeners: list[Callable[[Any], None]] = []
        node.add_pre_set_parameters_callback(self._coerce_integers)
        node.add_on_set_parameters_callback(self._check)
        node.add_post_set_parameters_callback(self._apply)

    def values(self, changes=()) -> dict[str, Any]:
        """All parameter values by name, with ``changes`` (Parameters) applied on top."""
        values = {name: self._node.get_parameter_or(name).value for name in self._names}
        values.update({p.name: p.value for p in changes})
        return values

    def on_change(self, listener: Callable[[Any], None]) -> None:
        self._listeners.append(listener)

    def declare(self, specs: list[Spec]) -> None:
        """Declare more parameters (a new model's per-joint ones); those declared already stay."""
        for spec in specs:
            if not self._node.has_parameter(spec.name):
                _declare(self._node, spec)
                self._names.append(spec.name)

    def _coerce_integers(self, parameters: list[Parameter]) -> list[Parameter]:
        """Let `ros2 param set ... payload.mass 3` mean 3.0 for a double parameter."""
        coerced = []
        for p in parameters:
            wanted = self._type_of(p.name)
            if wanted == Parameter.Type.DOUBLE and p.type_ == Parameter.Type.INTEGER:
                p = Parameter(p.name, Parameter.Type.DOUBLE, float(p.value))
            elif wanted == Parameter.Type.DOUBLE_ARRAY and p.type_ == Parameter.Type.INTEGER_ARRAY:
                p = Parameter(p.name, Parameter.Type.DOUBLE_ARRAY, [float(x) for x in p.value])
            coerced.append(p)
        return coerced

    def _type_of(self, name: str):
        if not self._node.has_parameter(name):
            return None
        return Parameter.Type(self._node.describe_parameter(name).type)

    def _check(self, parameters: list[Parameter]) -> SetParametersResult:
        """Build the whole new configuration; refuse the change if that fails."""
        values = self.values(parameters)
        try:
            self._pending = (values, self._build(values))
        except ValueError as error:
            self._pending = None
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply(self, parameters: list[Parameter]) -> None:
        """Swap in the configuration built by _check for exactly these values."""
        pending, self._pending = self._pending, None
        if pending is None or pending[0] != self.values():  # not the change just checked
            return
        self.replace(pending[1])

    def replace(self, configuration) -> None:
        """Swap in a configuration built from the current values (and an input from outside
        the parameters, such as a new robot_description). None: nothing to run on yet."""
        self.current = configuration
        if configuration is not None:
            for listener in self._listeners:
                listener(configuration)


def _declare(node: Node, spec: Spec):
    try:
        return node.declare_parameter(spec.name, spec.default, spec.descriptor()).value
    except InvalidParameterTypeException:
        kind = spec.default if isinstance(spec.default, Parameter.Type) else Parameter.Type.from_parameter_value(spec.default)
        hint = "; write doubles with a decimal point, e.g. 2.0" if "DOUBLE" in kind.name else ""
        raise ValueError(f"{spec.name}: expected a value of type {kind.name.lower()}{hint}") from None
    except InvalidParameterValueException as error:
        raise ValueError(f"{spec.name}: {error}") from None
