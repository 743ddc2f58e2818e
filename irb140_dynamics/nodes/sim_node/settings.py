"""sim_node's own parameters, and the simulation's setup built from all of them at once."""

from __future__ import annotations

from rclpy.parameter import Parameter

from irb140_dynamics.core import RobotModel
from irb140_dynamics.core.errors import check_choice
from irb140_dynamics.ros.parameters.arm import STAND_IN
from irb140_dynamics.ros.parameters.specs import MAX_QOS_DEPTH, Spec
from irb140_dynamics.sim.engine import DEFAULT_INTEGRATOR, SimulatedArm
from irb140_dynamics.sim.mjcf import INTEGRATORS
from irb140_dynamics.sim.simulation import Setup, initial_positions

NODE_PARAMETERS = [
    Spec("rate", 1000.0, "steps (and joint_states) per second of simulated time", "Hz", True, 1.0, 100000.0),
    Spec("substeps", 1, "MuJoCo steps per step (integration step 1 / (rate * substeps))", "", True, 1, 1000),
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
        maximum=3600.0,
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
        "after startup and each ~/reset the arm stays on its brakes until the first command and at "
        "least this long (simulated time)",
        "s",
        minimum=0.0,
        maximum=3600.0,
    ),
    Spec("noise.position", 0.0, "std dev of the noise on the published positions", "rad", minimum=0.0, maximum=10.0),
    Spec("noise.effort", 0.0, "std dev of the noise on the published efforts", "N m", minimum=0.0, maximum=1e4),
    Spec(
        "thread_priority",
        0,
        "SCHED_FIFO priority (1..99) of the stepping and executor threads, as "
        "ros2_control's controller manager runs its loop; 0 = ordinary scheduling",
        read_only=True,
        minimum=0,
        maximum=99,
    ),
    Spec("qos.depth", 10, "queue depth of joint_states and effort_commands", "", True, 1, MAX_QOS_DEPTH),
]


def build_setup(values: dict) -> Setup:
    """Validate what the descriptors cannot, and compile the MuJoCo model here, not on a step."""
    model = RobotModel.from_params(values)
    waiting = model.joint_names == STAND_IN.joint_names  # checked on a stand-in until a URDF comes
    check_choice("integrator", values["integrator"], INTEGRATORS)
    engine = SimulatedArm(model, 1.0 / values["rate"], values["substeps"], values["integrator"])
    return Setup(
        engine,
        initial_positions(model, None if waiting else values["initial_positions"]),
        values["command_timeout"],
        values["reset_hold"],
        values["noise.position"],
        values["noise.effort"],
    )
