"""Gravity compensation closes the loop: sim_node (the true arm, in MuJoCo) and id_node
(effort_commands = g(q)) as their own processes, as `ros2 run` starts them, hold the arm
still where it falls without commands."""

import time

import numpy as np
import pytest
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from irb140_dynamics.core import RigidBody, gravity, irb140
from irb140_dynamics.sim.engine import SimulatedArm

from ..support.node_process import TIMEOUT

POSE = [0.0, -0.5, 0.5, 0.0, 0.5, 0.0]  # rad
PAYLOAD = RigidBody(3.0, (0.02, 0.0, 0.05))  # both nodes' model: the true one
MODEL_ARGS = ["-p", "payload.mass:=3.0", "-p", "payload.com:=[0.02, 0.0, 0.05]"]
HOLD = 0.5  # s: the arm is held at POSE after ~/reset while the commands for POSE come in
DURATION = 5.0  # s
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
def test_gravity_compensation_holds_the_arm(probe, process):  # noqa: F811
    process(
        "irb140_dynamics.nodes.sim_node.node",
        *MODEL_ARGS,
        "-p",
        f"initial_positions:={POSE}",
        "-p",
        f"reset_hold:={HOLD}",
    )
    process(
        "irb140_dynamics.nodes.id_node.node",
        *MODEL_ARGS,
        "-p",
        "effort_commands.enabled:=true",
        "-p",
        "effort_commands.source:=gravity",
    )
    states = []
    probe.create_subscription(JointState, "joint_states", states.append, 1000)
    probe.spin_until(lambda: states and np.any(states[-1].effort))  # the loop is closed

    client = probe.create_client(Trigger, "/sim_node/reset")
    assert client.wait_for_service(timeout_sec=TIMEOUT)
    future = client.call_async(Trigger.Request())
    probe.spin_until(future.done)
    assert future.result().success
    replied = time.time_ns()  # sim_node stamps on the system clock: later states are after the reset

    end = replied + round((HOLD + DURATION + 0.1) * 1e9)
    probe.spin_until(lambda: states and stamp(states[-1]) > end, timeout=DURATION + HOLD + TIMEOUT)
    after_reset = [msg for msg in states if stamp(msg) > replied]
    assert after_reset[0].position.tolist() == POSE and not np.any(after_reset[0].effort)  # held at first
    released = [msg for msg in after_reset if np.any(msg.effort)]
    assert stamp(released[-1]) - stamp(released[0]) > DURATION * 1e9
    assert len(released) > 1000  # of the 5000 states: the probe keeps up with most
    position = np.array([msg.position for msg in released])
    drift = np.abs(position - POSE).max()
    assert drift < DRIFT, f"drifted {drift} rad"
