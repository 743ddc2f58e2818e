"""Gravity compensation closes the loop: sim_node (the true arm, in MuJoCo) and id_node
(effort_commands = g(q)) as their own processes, as `ros2 run` starts them, hold the arm
still where it falls without commands.

The loop runs in lockstep on simulated time (sim_node `lockstep:=true`, id_node
`use_sim_time:=true`, docs/sim.md, Lockstep): each state k+1 is one engine step with the
command id_node computed from state k, so the arm's motion does not depend on the
machine's load (in real time, on two busy cores, commands came late and the arm drifted
0.029 rad). The probe sees every state; each after the hold is checked to carry as its
effort g of the state before it (to 1e-12): no step went without its command or took a
stale one.
"""

import numpy as np
import pytest
from sensor_msgs.msg import JointState

from irb140_dynamics.core import RigidBody, gravity, irb140
from irb140_dynamics.sim.engine import SimulatedArm

POSE = [0.0, -0.5, 0.5, 0.0, 0.5, 0.0]  # rad
PAYLOAD = RigidBody(3.0, (0.02, 0.0, 0.05))  # both nodes' model: the true one
MODEL_ARGS = ["-p", "payload.mass:=3.0", "-p", "payload.com:=[0.02, 0.0, 0.05]"]
HOLD = 0.5  # s of simulated time: the arm is held at POSE after startup while the commands for POSE come in
DURATION = 5.0  # s of simulated time
RATE = 1000.0  # Hz: steps of simulated time, as the two checks below step
PERIOD = round(1e9 / RATE)  # ns
READY = 120.0  # s: both processes started and the loop closed, on two busy cores
LOOP = 60 * (HOLD + DURATION)  # s: the loop's wall-clock time, far beyond what a busy machine needs
FALL, DRIFT = 0.1, 1e-3  # rad: without commands it falls more than FALL in 1 s; held, drifts < DRIFT


def test_without_commands_the_arm_falls():
    arm = SimulatedArm(irb140(payload=PAYLOAD))
    arm.reset(POSE)
    for _ in range(1000):  # 1 s at 1 kHz
        arm.step(np.zeros(6))
    assert np.abs(arm.q - POSE).max() > FALL


def test_compensating_with_a_wrong_payload_drifts():
    """The closed-loop check below can fail: the gravity of the model without the payload,
    applied to the true arm (as a loop at 1 kHz would), lets it drift far beyond DRIFT."""
    arm, unloaded = SimulatedArm(irb140(payload=PAYLOAD)), irb140()
    arm.reset(POSE)
    for _ in range(round(DURATION * 1000)):
        arm.step(gravity(unloaded, arm.q))
    assert np.abs(arm.q - POSE).max() > 100 * DRIFT


def stamp(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


@pytest.mark.slow
def test_gravity_compensation_holds_the_arm(stream_probe, process):  # noqa: F811
    probe = stream_probe
    states = {}  # by stamp: sim_node publishes a state again, same stamp, while no command answers it
    probe.create_subscription(JointState, "joint_states", lambda msg: states.__setitem__(stamp(msg), msg), 10000)
    sim = process(
        "irb140_dynamics.nodes.sim_node.node",
        *MODEL_ARGS,
        *("-p", f"initial_positions:={POSE}", "-p", f"reset_hold:={HOLD}"),
        *("-p", "lockstep:=true", "-p", f"rate:={RATE}", "-p", "qos.depth:=10000"),
    )
    # Nothing steps before id_node answers: sim_node publishes its first state again every
    # lockstep_timeout. Once the probe has one, it is matched and will miss none of the loop.
    probe.spin_until(lambda: states, timeout=READY)
    controller = process(
        "irb140_dynamics.nodes.id_node.node",
        *MODEL_ARGS,
        *("-p", "effort_commands.enabled:=true", "-p", "effort_commands.source:=gravity"),
        *("-p", "use_sim_time:=true", "-p", "qos.depth:=1"),
    )
    released = round(HOLD * 1e9)  # [ns] simulated: the startup hold ends, the commands apply
    end = released + round(DURATION * 1e9)
    probe.spin_until(lambda: states and max(states) >= end, timeout=READY + LOOP)
    for node in (controller, sim):  # every state is in: the loop would go on at full speed during the checks
        node.kill()

    held = [msg for s, msg in sorted(states.items()) if s <= released]
    assert all(msg.position.tolist() == POSE and not np.any(msg.effort) for msg in held)  # still at first
    stamps = [s for s in sorted(states) if released < s <= end]
    assert stamps == [released + k * PERIOD for k in range(1, len(stamps) + 1)], "a step missing or misplaced"
    assert len(stamps) == round(DURATION * RATE), "the probe missed joint states"
    model = irb140(payload=PAYLOAD)
    for s in stamps:  # the command applied in each step is g of the state before it
        before, after = states[s - PERIOD], states[s]
        expected = gravity(model, before.position)
        np.testing.assert_allclose(after.effort, expected, rtol=1e-12, atol=1e-9, err_msg=f"command of {s - PERIOD}")
    position = np.array([states[s].position for s in stamps])
    drift = np.abs(position - POSE).max()
    assert drift < DRIFT, f"drifted {drift} rad"
