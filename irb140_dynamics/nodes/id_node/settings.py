"""id_node's parameters and the settings it runs on, checked whole (see nodes.id_node.node)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from irb140_dynamics.core import RigidBody, RobotModel
from irb140_dynamics.core.codegen.kernels import Preparation, prepare
from irb140_dynamics.core.codegen.recipes import WITH_FRICTION
from irb140_dynamics.core.model.rigid_body import MAX_MASS
from irb140_dynamics.core.monitoring import collision as observer
from irb140_dynamics.core.monitoring.wrench import FRAMES
from irb140_dynamics.core.payload.limits import RATED_PAYLOAD, derive_torque_limits
from irb140_dynamics.core.payload.stop import stopping
from irb140_dynamics.core.trajectories.tracking import ACCELERATION_MODES, EFFORT_SOURCES, Gains
from irb140_dynamics.ros.parameters.specs import MAX_TORQUE, QOS_PARAMETERS, RELIABILITIES, Spec, check_choice

MAX_GAIN = 1e6  # computed-torque gains
DEFAULT_KP, DEFAULT_KD = 400.0, 40.0  # 1/s^2, 1/s: natural frequency 20 rad/s, critically damped
MAX_MARKER_RATE = 100.0  # Hz

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
        maximum=1e6,
    ),
    Spec(
        "reference_timeout",
        0.5,
        "a ~/reference is let go this long after its last point (node clock); 0 = never",
        "s",
        minimum=0.0,
        maximum=1e6,
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
    Spec(
        "collision.observer_gain",
        observer.DEFAULT_GAIN,
        "gain K of the momentum observer: external torques are seen through a lag of time constant 1/K",
        "1/s",
        minimum=observer.MIN_GAIN,
        maximum=observer.MAX_GAIN,
    ),
    Spec(
        "external_wrench.frame",
        "tip",
        "axes of external_wrench: 'tip' (the tip link's, e.g. flange) or 'base' (the base link's); "
        "the torque is about the flange origin in both",
    ),
    Spec(
        "markers.rate",
        10.0,
        "~/markers (visualization_msgs/MarkerArray) at most this often, after new joint states; 0 = off",
        "Hz",
        minimum=0.0,
        maximum=MAX_MARKER_RATE,
        read_only=True,
    ),
    *QOS_PARAMETERS,
]


def PER_JOINT_PARAMETERS(joint_names) -> list[Spec]:
    thresholds = [
        Spec(
            f"{name}.collision_threshold",
            0.0,
            "a collision is flagged while |external torque| exceeds this; 0 = off",
            "N m",
            minimum=0.0,
            maximum=MAX_TORQUE,
        )
        for name in joint_names
    ]
    gains = [
        Spec(f"{name}.{kind}", default, f"computed-torque {what} gain", unit, minimum=0.0, maximum=MAX_GAIN)
        for name in joint_names
        for kind, default, what, unit in (
            ("kp", DEFAULT_KP, "position", "1/s^2"),
            ("kd", DEFAULT_KD, "velocity", "1/s"),
        )
    ]
    return thresholds + gains


@dataclass(frozen=True)
class CollisionSettings:
    gain: float  # 1/s
    thresholds: np.ndarray  # N m, 0 = off


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
    wrench_frame: str  # "tip" or "base"
    rated_payload: RigidBody = RATED_PAYLOAD  # the torque limits are derived from it (joints without torque_limit)
    torque_limits: tuple[float, ...] | None = None  # N m (inf: none), the payload check's; set by finish_settings
    kernels: Preparation | None = None  # how the model's kernels were made ready (set by finish_settings)


def check_settings(values: dict) -> IdNodeSettings:
    """Validate what the descriptors cannot (before a change is accepted); kernels not compiled yet."""
    model = RobotModel.from_params(values)
    check_choice("acceleration.mode", values["acceleration.mode"], ACCELERATION_MODES)
    check_choice("effort_commands.source", values["effort_commands.source"], EFFORT_SOURCES)
    check_choice("qos.reliability", values["qos.reliability"], RELIABILITIES)
    check_choice("external_wrench.frame", values["external_wrench.frame"], FRAMES)

    def per_joint(kind: str) -> np.ndarray:
        return np.array([values[f"{name}.{kind}"] for name in model.joint_names], dtype=float)

    return IdNodeSettings(
        model,
        values["acceleration.mode"],
        values["acceleration.cutoff_frequency"],
        values["reference_timeout"],
        values["effort_commands.source"],
        CollisionSettings(values["collision.observer_gain"], per_joint("collision_threshold")),
        Gains(per_joint("kp"), per_joint("kd")),
        values["external_wrench.frame"],
        RigidBody.validated("rated_payload", values["rated_payload.mass"], values["rated_payload.com"]),
    )


KERNELS = (WITH_FRICTION, "gravity_torques", "momentum", "monitor")  # what a message uses (rnea, gravity; the observer)
NATIVE_WAIT = 30.0  # s: the longest a new model waits for its kernels' C (docs/id_node.md); then Python meanwhile
LIMITS_TIME = 5.0  # s: the search for derived limits stops by then (what it found stands)


def finish_settings(settings: IdNodeSettings, previous: IdNodeSettings | None) -> IdNodeSettings:
    """Make the kernels the messages use native (compiled as C, or loaded from the cache)
    and derive the markers' torque limits (the payload check's: given, else derived from
    the rated payload within LIMITS_TIME; inf: none), each unless ``previous`` has them for
    the same arm. Run before the first message, and off the executor after a change while
    the old settings answer; a compile longer than NATIVE_WAIT goes on in the background,
    the Python form answering meanwhile."""
    if previous is not None and previous.model == settings.model:
        kernels = previous.kernels
        settings = replace(settings, model=previous.model)
    else:
        kernels = prepare(settings.model, timeout=NATIVE_WAIT, names=KERNELS)
    model = settings.model
    if previous is not None and (previous.model.joints, previous.model.gravity, previous.rated_payload) == (
        model.joints,
        model.gravity,
        settings.rated_payload,
    ):  # the payload in use does not enter them
        limits = previous.torque_limits
    else:
        with stopping(seconds=LIMITS_TIME):
            limits = derive_torque_limits(model, settings.rated_payload).values
    return replace(settings, torque_limits=limits, kernels=kernels)


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
