"""id_node's parameters and the settings it runs on, validated whole (see nodes.id_node.node)."""

from __future__ import annotations

from dataclasses import dataclass, replace

from irb140_dynamics.core import RigidBody, RobotModel
from irb140_dynamics.core.codegen.kernels import Preparation, prepare
from irb140_dynamics.core.codegen.recipes import WITH_FRICTION
from irb140_dynamics.core.model.rigid_body import MAX_MASS
from irb140_dynamics.core.payload.limits import RATED_PAYLOAD, derive_torque_limits
from irb140_dynamics.core.payload.stop import stopping
from irb140_dynamics.nodes.id_node.collision import (
    COLLISION_PARAMETERS,
    CollisionSettings,
    build_collision_settings,
    collision_threshold_specs,
)
from irb140_dynamics.nodes.id_node.markers import MARKER_PARAMETERS
from irb140_dynamics.nodes.id_node.tracking import Gains, build_gains, gain_specs
from irb140_dynamics.nodes.id_node.wrench import WRENCH_PARAMETERS, check_wrench_frame
from irb140_dynamics.ros.parameters.specs import QOS_PARAMETERS, RELIABILITIES, Spec, check_choice

ACCELERATION_MODES = ("zero", "differentiate")
EFFORT_SOURCES = ("feedforward", "gravity", "computed_torque")
MAX_CUTOFF_FREQUENCY = 1e6  # Hz
MAX_TIMEOUT = 1e6  # s

NODE_PARAMETERS = [
    Spec(
        "acceleration.mode",
        "zero",
        "qdd when no ~/reference gives it: 'zero', or 'differentiate' the measured velocities (low-pass "
        "filtered; for monitoring: as a command it would feed the measured acceleration back, "
        "so effort_commands never use it)",
    ),
    Spec(
        "acceleration.cutoff_frequency",
        20.0,
        "cut-off of the velocity differentiation filter",
        "Hz",
        minimum=1e-3,
        maximum=MAX_CUTOFF_FREQUENCY,
    ),
    Spec(
        "reference_timeout",
        0.5,
        "a ~/reference is let go this long after its last point (node clock); 0 = never",
        "s",
        minimum=0.0,
        maximum=MAX_TIMEOUT,
    ),
    Spec(
        "effort_commands.enabled", False, "also publish torques on effort_commands (Float64MultiArray)", read_only=True
    ),
    Spec(
        "effort_commands.source",
        "feedforward",
        "which torques go to effort_commands: 'feedforward', 'gravity' or 'computed_torque'",
    ),
    Spec(
        "rated_payload.mass",
        6.0,
        "the rated payload the markers' torque limits are derived from, for joints without torque_limit "
        "(as payload_check_node's)",
        "kg",
        minimum=0.0,
        maximum=MAX_MASS,
    ),
    Spec("rated_payload.com", [0.0, 0.0, 0.0], "its centre of mass, in the flange frame", "m"),
    *COLLISION_PARAMETERS,
    *WRENCH_PARAMETERS,
    *MARKER_PARAMETERS,
    *QOS_PARAMETERS,
]


def PER_JOINT_PARAMETERS(joint_names) -> list[Spec]:
    return collision_threshold_specs(joint_names) + gain_specs(joint_names)


@dataclass(frozen=True)
class IdNodeSettings:
    """What the node runs on, built and validated from all of its parameters at once."""

    model: RobotModel
    acceleration_mode: str
    cutoff_frequency: float
    reference_timeout: float
    effort_source: str
    collision: CollisionSettings
    gains: Gains
    wrench_frame: str  # external_wrench.frame: "tip" or "base"
    rated_payload: RigidBody = RATED_PAYLOAD  # the torque limits are derived from it (joints without torque_limit)
    torque_limits: tuple[float, ...] | None = None  # N m (inf: none), the payload check's; set by finish_settings
    kernels: Preparation | None = None  # how the model's kernels were made ready (set by finish_settings)


def check_settings(values: dict) -> IdNodeSettings:
    """Validate what the descriptors cannot (before a change is accepted); kernels not compiled yet."""
    model = RobotModel.from_params(values)
    check_choice("acceleration.mode", values["acceleration.mode"], ACCELERATION_MODES)
    check_choice("effort_commands.source", values["effort_commands.source"], EFFORT_SOURCES)
    check_choice("qos.reliability", values["qos.reliability"], RELIABILITIES)
    return IdNodeSettings(
        model,
        values["acceleration.mode"],
        values["acceleration.cutoff_frequency"],
        values["reference_timeout"],
        values["effort_commands.source"],
        build_collision_settings(values, model.joint_names),
        build_gains(values, model.joint_names),
        check_wrench_frame(values),
        RigidBody.validated("rated_payload", values["rated_payload.mass"], values["rated_payload.com"]),
    )


KERNELS = (WITH_FRICTION, "gravity_torques", "momentum", "monitor")  # what a message uses (rnea, gravity; the observer)
NATIVE_WAIT = 30.0  # s: the longest a new model waits for its kernels' C (docs/id_node.md); then Python meanwhile


def finish_settings(settings: IdNodeSettings, previous: IdNodeSettings | None) -> IdNodeSettings:
    """Make the kernels the messages use native (compiled as C, or loaded from the cache),
    here and not on a message: at startup before the first message, after a change off the
    executor while the old model answers (see core.codegen.kernels.prepare), and derive the
    markers' torque limits unless the arm and the rated payload are those of ``previous``.
    A compile longer than NATIVE_WAIT goes on in the background, the Python form answering
    meanwhile."""
    if previous is not None and previous.model == settings.model:
        kernels = previous.kernels
        settings = replace(settings, model=previous.model)
    else:
        kernels = prepare(settings.model, timeout=NATIVE_WAIT, names=KERNELS)
    if _same_limits(settings, previous):
        limits = previous.torque_limits
    else:
        limits = torque_limits(settings.model, settings.rated_payload)
    return replace(settings, torque_limits=limits, kernels=kernels)


def _same_limits(settings: IdNodeSettings, previous: IdNodeSettings | None) -> bool:
    """The torque limits of ``previous`` hold: the same joints, gravity and rated payload
    (the payload in use does not enter them)."""
    return previous is not None and (previous.model.joints, previous.model.gravity, previous.rated_payload) == (
        settings.model.joints,
        settings.model.gravity,
        settings.rated_payload,
    )


LIMITS_TIME = 5.0  # s: the search for derived limits stops by then (what it found stands)


def torque_limits(model: RobotModel, rated: RigidBody = RATED_PAYLOAD) -> tuple[float, ...]:
    """The limits the markers colour the joints by: the payload check's (given, else derived
    from the ``rated`` payload, searched for at most LIMITS_TIME; inf: none)."""
    with stopping(seconds=LIMITS_TIME):
        return derive_torque_limits(model, rated).values


def kernels_text(kernels: Preparation | None) -> str:
    """How the model's kernels run, for the log: native (and how long that took) or Python."""
    if kernels is None:
        return "kernels: Python form"
    if kernels.native:
        return f"kernels: native (compiled or loaded in {kernels.seconds:.1f} s)"
    if kernels.compiling:
        return (
            f"kernels: Python form for now: compiling them as C took over {NATIVE_WAIT:g} s, "
            "native once the compile is done"
        )
    return f"kernels: Python form ({kernels.reason}; traced in {kernels.seconds:.1f} s)"
