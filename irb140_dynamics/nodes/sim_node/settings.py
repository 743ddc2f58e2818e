"""sim_node's parameters and the settings it runs on, validated whole (see the node)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rclpy.parameter import Parameter
from std_msgs.msg import Float64MultiArray

from irb140_dynamics.core import RobotModel
from irb140_dynamics.ros.messages.joint_messages import BadMessage
from irb140_dynamics.ros.parameters.arm import STAND_IN
from irb140_dynamics.ros.parameters.specs import MAX_QOS_DEPTH, Spec, check_choice
from irb140_dynamics.sim.engine import DEFAULT_INTEGRATOR, SimulatedArm
from irb140_dynamics.sim.mjcf import INTEGRATORS

MAX_SUBSTEPS = 1000
MAX_TIME = 3600.0  # s: command_timeout, reset_hold
MAX_POSITION_NOISE = 10.0  # rad (std dev)
MAX_EFFORT_NOISE = 1e4  # N m (std dev)
NODE_PARAMETERS = [
    Spec(
        "rate",
        1000.0,
        "simulation steps (and joint_states messages) per second of simulated time",
        "Hz",
        minimum=1.0,
        maximum=100000.0,
        read_only=True,
    ),
    Spec(
        "substeps",
        1,
        "MuJoCo steps per step (the integration step is 1 / (rate * substeps))",
        read_only=True,
        minimum=1,
        maximum=MAX_SUBSTEPS,
    ),
    Spec("integrator", DEFAULT_INTEGRATOR, f"MuJoCo's integrator: {', '.join(INTEGRATORS)}", read_only=True),
    Spec(
        "lockstep",
        False,
        "step once per command instead of in real time, and publish /clock (simulated "
        "time; run the other nodes with use_sim_time: true)",
        read_only=True,
    ),
    Spec(
        "lockstep_timeout",
        0.5,
        "in lockstep: with no command for this long (wall clock; a stall of sim_node "
        "itself does not count), the last state and /clock are published again",
        "s",
        minimum=1e-3,
        maximum=60.0,
        read_only=True,
    ),
    Spec(
        "command_timeout",
        0.1,
        "zero torque once the last command is older than this; 0 = never "
        "(in real time; in lockstep each step applies the command it answers)",
        "s",
        minimum=0.0,
        maximum=MAX_TIME,
    ),
    Spec(
        "initial_positions",
        Parameter.Type.DOUBLE_ARRAY,
        "where the arm starts and ~/reset puts it, model joint order; not given or empty = all zero",
        "rad",
    ),
    Spec(
        "reset_hold",
        0.0,
        "after startup and each ~/reset the arm is held still (brakes on, no torque) this long (simulated time)",
        "s",
        minimum=0.0,
        maximum=MAX_TIME,
    ),
    Spec(
        "noise.position",
        0.0,
        "std dev of the noise added to the published positions",
        "rad",
        minimum=0.0,
        maximum=MAX_POSITION_NOISE,
    ),
    Spec(
        "noise.effort",
        0.0,
        "std dev of the noise added to the published efforts",
        "N m",
        minimum=0.0,
        maximum=MAX_EFFORT_NOISE,
    ),
    Spec(
        "thread_priority",
        0,
        "SCHED_FIFO priority (1..99) of the stepping and executor threads, as "
        "ros2_control's controller manager runs its loop; 0 = ordinary scheduling",
        read_only=True,
        minimum=0,
        maximum=99,
    ),
    Spec(
        "qos.depth",
        10,
        "queue depth of joint_states and effort_commands",
        read_only=True,
        minimum=1,
        maximum=MAX_QOS_DEPTH,
    ),
]


@dataclass(frozen=True)
class SimNodeSettings:
    """What the node runs on, built and validated from all of its parameters at once."""

    model: RobotModel
    engine: SimulatedArm  # a fresh engine for this model: taken over (with the state) when applied
    initial_positions: np.ndarray
    command_timeout: float
    reset_hold: float
    position_noise: float
    effort_noise: float


def build_settings(values: dict) -> SimNodeSettings:
    """Validate what the descriptors cannot and compile the MuJoCo model here, not on a step."""
    model = RobotModel.from_params(values)
    waiting = model.joint_names == STAND_IN.joint_names  # checked on a stand-in until a URDF comes
    check_choice("integrator", values["integrator"], INTEGRATORS)
    engine = SimulatedArm(model, 1.0 / values["rate"], values["substeps"], values["integrator"])
    initial = np.zeros(model.n) if waiting else initial_positions(model, values["initial_positions"])
    return SimNodeSettings(
        model,
        engine,
        initial,
        values["command_timeout"],
        values["reset_hold"],
        values["noise.position"],
        values["noise.effort"],
    )


def initial_positions(model: RobotModel, values) -> np.ndarray:
    """The initial positions, or ValueError: one per joint (none: zeros), within the limits."""
    q = np.zeros(model.n) if not values else np.array(values, dtype=float)
    if q.shape != (model.n,):
        raise ValueError(f"initial_positions: expected {model.n} values, got {len(q)}")
    for joint, x in zip(model.joints, q):
        lower, upper = joint.position_limits
        if not lower <= x <= upper:
            raise ValueError(f"initial_positions: {joint.name} at {x} rad is outside its limits [{lower}, {upper}]")
    return q


def read_command(msg: Float64MultiArray, n: int) -> np.ndarray:
    """The torques of a command, or BadMessage: n finite numbers."""
    if len(msg.data) != n:
        raise BadMessage("length_mismatch", f"{len(msg.data)} torques for {n} joints")
    tau = np.array(msg.data, dtype=float)
    if not np.isfinite(tau).all():
        raise BadMessage("not_finite", f"torques are not finite: {tau.tolist()}")
    return tau
