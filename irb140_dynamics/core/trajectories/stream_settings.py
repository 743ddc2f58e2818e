"""What a stream of joint states is answered with (id_node's settings), checked whole from a
node's parameter values (``check_settings``) and then made ready to run (``finish_settings``:
the kernels native, the markers' torque limits derived). No ROS: the node hands in a dict.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from irb140_dynamics.core.codegen.kernels import Preparation, prepare
from irb140_dynamics.core.codegen.recipes import WITH_FRICTION
from irb140_dynamics.core.errors import check_choice
from irb140_dynamics.core.ft_sensor.contact import FRAMES as FT_FRAMES
from irb140_dynamics.core.model.rigid_body import RigidBody
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.monitoring.wrench import FRAMES
from irb140_dynamics.core.payload.limits import RATED_PAYLOAD, derive_torque_limits
from irb140_dynamics.core.payload.stop import stopping
from irb140_dynamics.core.trajectories.tracking import ACCELERATION_MODES, EFFORT_SOURCES, Gains

KERNELS = (WITH_FRICTION, "gravity_torques", "momentum", "monitor")  # what a message uses (rnea, gravity; the observer)
NATIVE_WAIT = 30.0  # s: the longest a new model waits for its kernels' C (docs/id_node.md); then Python meanwhile
LIMITS_TIME = 5.0  # s: the search for derived limits stops by then (what it found stands)


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
    wrench_links: tuple[str, ...] = ()  # URDF links whose wrenches are estimated (monitoring.link_wrenches)
    ft_link: str = ""  # the link of a wrist force/torque sensor, "" = none (core.ft_sensor)
    ft_frame: str = "sensor"  # the axes of its contact wrench: "sensor" or "base"
    rated_payload: RigidBody = RATED_PAYLOAD  # the torque limits are derived from it (joints without torque_limit)
    torque_limits: tuple[float, ...] | None = None  # N m (inf: none), the payload check's; set by finish_settings
    kernels: Preparation | None = None  # how the model's kernels were made ready (set by finish_settings)


def check_settings(values: dict) -> IdNodeSettings:
    """Validate what the descriptors cannot (before a change is accepted); kernels not compiled yet."""
    model = RobotModel.from_params(values)
    check_choice("acceleration.mode", values["acceleration.mode"], ACCELERATION_MODES)
    check_choice("effort_commands.source", values["effort_commands.source"], EFFORT_SOURCES)
    check_choice("external_wrench.frame", values["external_wrench.frame"], FRAMES)
    links = tuple(values.get("external_wrench.links") or ())
    if links and values["external_wrench.frame"] != "tip":
        raise ValueError("external_wrench.frame: with external_wrench.links each wrench is in its link's axes ('tip')")
    ft_link, ft_frame = values.get("ft_sensor.link", ""), values.get("ft_contact_wrench.frame", "sensor")
    check_choice("ft_contact_wrench.frame", ft_frame, FT_FRAMES)

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
        links,
        ft_link,
        ft_frame,
        RigidBody.validated("rated_payload", values["rated_payload.mass"], values["rated_payload.com"]),
    )


def finish_settings(settings: IdNodeSettings, previous: IdNodeSettings | None) -> IdNodeSettings:
    """Make the kernels the messages use native (compiled as C, or loaded from the cache)
        and derive the markers' torque limits (the payload check's: given, else derived from
        the rated payload within LIMITS_TIME; on a tree or with mimic joints, the given ones
    only; inf: none), each unless ``previous`` has them for
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
    elif not model.is_chain:  # the payload analysis is a chain's: a tree's markers use the given limits only
        limits = tuple(limit if limit > 0 else float("inf") for limit in model.torque_limits)
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
