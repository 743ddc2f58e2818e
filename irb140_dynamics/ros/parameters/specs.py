"""The parameters every node shares: where the arm comes from, the model's own (with the
finite ranges of its numbers), the joint_states QoS."""

from __future__ import annotations

import math
from typing import Any

from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy

from irb140_dynamics.core.io.arm_source import DEFAULT_ROBOT_NAME, HELD, URDF_PARAMETERS
from irb140_dynamics.core.model.joints import MAX_FRICTION, MAX_TORQUE_LIMIT, param_prefix
from irb140_dynamics.core.model.rigid_body import MAX_MASS
from irb140_dynamics.ros.parameters.spec import Spec

# The finite ranges of the model's numbers: wide, to keep inf, nan and 1e308 out, not to
# judge the robot; masses (kg), torque limits and friction the core's own caps (a URDF's too).
MAX_TORQUE = MAX_TORQUE_LIMIT  # N m (torque limits, collision thresholds)
MAX_QOS_DEPTH = 10_000  # messages: 10 s at 1 kHz; DDS may reserve memory for the whole depth
RELIABILITIES = {"best_effort": ReliabilityPolicy.BEST_EFFORT, "reliable": ReliabilityPolicy.RELIABLE}
QOS_PARAMETERS = [
    Spec(
        "qos.reliability",
        "best_effort",
        "joint_states (and ft_wrench) subscription reliability: 'best_effort' (takes reliable and "
        "best-effort publishers) or 'reliable'",
        read_only=True,
    ),
    Spec(
        "qos.depth",
        10,
        "queue depth of joint_states, ~/reference and the torque topics",
        read_only=True,
        minimum=1,
        maximum=MAX_QOS_DEPTH,
    ),
]
JOINT_NUMBERS = (  # each joint's numbers of 0 and up: (name suffix, description, unit, maximum)
    ("torque_limit", "joint torque limit, 0 = none given", "N m", MAX_TORQUE),
    ("velocity_limit", "joint speed limit, 0 = none given", "rad/s", 1e4),
    ("acceleration_limit", "joint acceleration limit, 0 = none given", "rad/s^2", 1e7),
    ("friction.viscous", "viscous friction coefficient", "N m s/rad", MAX_FRICTION),
    ("friction.coulomb", "Coulomb friction level (smoothed, see friction.smoothing_velocity)", "N m", MAX_FRICTION),
    ("armature", "rotor inertia reflected through the gear, added to M's diagonal", "kg m^2", MAX_FRICTION),
)
MODEL_NAME = Spec(
    "model.name",
    DEFAULT_ROBOT_NAME,
    "the robot's name, the hardware_id of the nodes' /diagnostics (a URDF model: its <robot name>)",
    read_only=True,
)
SOURCE = Spec(
    "model.source",
    "parameters",
    "where the model comes from: 'parameters' (joint_names and <joint>.*) or 'robot_description' (URDF)",
    read_only=True,
)
DESCRIPTION_PARAMETERS = [  # model.source robot_description (read-only)
    Spec(name, default if default != () else Parameter.Type.STRING_ARRAY, description, read_only=True)
    for name, default, description in URDF_PARAMETERS
]


PAYLOAD_LINK = Spec(
    "payload.link",
    "",
    "the URDF link the payload hangs on (payload.com and .inertia in its frame); empty: the tip link "
    "(on a whole tree, a payload needs it)",
)


def joint_states_qos(node: Node) -> QoSProfile:
    """The joint_states subscription's QoS from the node's qos.* parameters."""
    reliability = RELIABILITIES[node.get_parameter("qos.reliability").value]
    return QoSProfile(depth=node.get_parameter("qos.depth").value, reliability=reliability)


def joint_names_spec(names: list[str]) -> Spec:
    """``joint_names``, with these names as its default."""
    return Spec("joint_names", list(names), "the model's joints, base to flange", read_only=True)


def model_specs(joint_names: list[str], defaults: dict[str, Any]) -> list[Spec]:
    """The model's parameters for these joints, the defaults those of the default model's
    file; its per-joint defaults only when the joints are its own (a params file naming
    other joints gives every value: nothing is silently borrowed)."""
    own = list(defaults.get("joint_names", [])) == list(joint_names)

    def default(name, kind):
        return defaults[name] if own and name in defaults else kind

    specs = [
        Spec("gravity", defaults.get("gravity", [0.0, 0.0, -9.81]), "gravity in the base frame", "m/s^2"),
        Spec(
            "friction.smoothing_velocity",
            defaults.get("friction.smoothing_velocity", 0.01),
            "Coulomb friction is coulomb * tanh(qd / this)",
            "rad/s",
            minimum=1e-9,
            maximum=1e3,
        ),
        *_body_specs(
            "payload", "the payload on the flange", "flange frame", lambda name, kind: defaults.get(name, kind)
        ),
        *(spec for spec in DESCRIPTION_PARAMETERS if spec.name == HELD),  # an arm of parameters: refused (read_arm)
    ]
    for name in joint_names:
        joint = param_prefix(name)  # the joint's parameter prefix (its name, if a parameter name)
        dh = f"{joint}.dh"
        specs += [
            Spec(
                dh,
                default(dh, Parameter.Type.DOUBLE_ARRAY),
                "standard DH row [a, alpha, d, theta_offset]",
                "m, rad, m, rad",
            ),
            *_body_specs(f"{joint}.link", f"the link {joint} moves", "its DH frame", default),
            *drive_specs(name, default),
        ]
    return specs


def drive_specs(name: str, default=lambda name, kind: kind) -> list[Spec]:
    """A joint's drive: its position limits and JOINT_NUMBERS (a URDF arm's too: what URDF
    has no sure place for)."""
    joint = param_prefix(name)
    limits = f"{joint}.position_limits"
    return [
        Spec(limits, default(limits, [-math.pi, math.pi]), "[lower, upper] joint position", "rad"),
        *(
            Spec(f"{joint}.{suffix}", default(f"{joint}.{suffix}", 0.0), text, unit, minimum=0.0, maximum=maximum)
            for suffix, text, unit, maximum in JOINT_NUMBERS
        ),
    ]


def _body_specs(prefix: str, what: str, frame: str, default) -> list[Spec]:
    """mass, com and inertia of a body: a payload's are none by default, a link's are to be given."""
    payload = prefix == "payload"
    mass, com, inertia = f"{prefix}.mass", f"{prefix}.com", f"{prefix}.inertia"
    double, array = Parameter.Type.DOUBLE, Parameter.Type.DOUBLE_ARRAY
    inertia_text = f"inertia of {what} about its centre of mass, [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]"
    return [
        Spec(mass, default(mass, 0.0 if payload else double), f"mass of {what}", "kg", minimum=0.0, maximum=MAX_MASS),
        Spec(com, default(com, [0.0] * 3 if payload else array), f"centre of mass of {what}, in {frame}", "m"),
        Spec(inertia, default(inertia, [0.0] * 6 if payload else array), inertia_text, "kg m^2"),
    ]
