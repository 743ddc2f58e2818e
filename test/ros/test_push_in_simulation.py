"""Pushing the simulated arm: sim_node applies ~/external_wrench to its flange and refuses bad
ones (counted, never applied); with id_node compensating gravity in lockstep (one step per
command, simulated time), a 20 N push shows on id_node's external_wrench within 5 %."""

import numpy as np
import pytest
from geometry_msgs.msg import WrenchStamped
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState

from irb140_dynamics.nodes.sim_node.node import SimNode

from ..support.ros_harness import running
from .test_sim_node import POSE, make, sim_with_controller, stamp

PUSH = np.array([0.0, 0.0, 20.0])  # N, along the flange's z (through the wrist centre: the light wrist stays put)
SETTLED = 0.1  # s of simulated time: 10/K, the observer's lag long gone
DURATION = 0.3  # s of simulated time the push is watched (the arm, free under it, moves a little)


def wrench(frame_id: str, force, torque=(0.0, 0.0, 0.0)) -> WrenchStamped:
    msg = WrenchStamped()
    msg.header.frame_id = frame_id
    msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = (float(x) for x in force)
    msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = (float(x) for x in torque)
    return msg


@pytest.fixture
def sim():
    with running(SimNode, parameter_overrides=make(lockstep=True)) as harness:
        harness.states = harness.listen(JointState, "joint_states", 1000)
        harness.pushes = harness.publisher(WrenchStamped, "/sim_node/external_wrench")
        yield harness


def received(sim, count: int) -> None:
    assert sim.spin_until(lambda: sim.node.counts["external_wrench.received"] >= count), "wrench not received"


def test_bad_wrenches_are_dropped_and_counted_never_applied(sim):
    assert sim.spin_until(lambda: sim.node.simulation.arm is not None)
    bad = [
        wrench("flange", [np.nan, 0.0, 0.0]),
        wrench("base_link", [0.0, np.inf, 0.0]),
        wrench("flange", [2e5, 0.0, 0.0]),  # beyond MAX_FORCE: absurd
        wrench("flange", [0.0, 0.0, 0.0], [0.0, 2e4, 0.0]),  # beyond MAX_TORQUE
        wrench("tool0", [10.0, 0.0, 0.0]),  # not this arm's link
        wrench("", [10.0, 0.0, 0.0]),
    ]
    for k, msg in enumerate(bad, start=1):
        sim.pushes.publish(msg)
        received(sim, k)
    counts = sim.node.counts
    assert counts["external_wrench.dropped"] == len(bad)
    assert counts["external_wrench.dropped_not_finite"] == 2 and counts["external_wrench.dropped_absurd_wrench"] == 2
    assert counts["external_wrench.dropped_unknown_frame"] == 2
    assert sim.node.simulation.held_push(sim.node._now()) == (None, "base")  # nothing held


def test_a_push_is_held_in_the_frame_it_names(sim):
    assert sim.spin_until(lambda: sim.node.simulation.arm is not None)
    sim.pushes.publish(wrench("flange", [1.0, 2.0, 3.0], [0.1, 0.2, 0.3]))
    received(sim, 1)
    values, frame = sim.node.simulation.held_push(sim.node._now())
    assert frame == "tip" and values.tolist() == [1.0, 2.0, 3.0, 0.1, 0.2, 0.3]
    sim.pushes.publish(wrench("base_link", [0.0, 0.0, 5.0]))
    received(sim, 2)
    values, frame = sim.node.simulation.held_push(sim.node._now())
    assert frame == "base" and values.tolist() == [0.0, 0.0, 5.0, 0.0, 0.0, 0.0]


def test_a_20_newton_push_shows_on_external_wrench_in_lockstep():
    with sim_with_controller(lockstep=True, rate=1000.0, **{"qos.depth": 1000}) as (harness, add_controller):
        add_controller(
            [
                Parameter("use_sim_time", value=True),
                Parameter("effort_commands.enabled", value=True),
                Parameter("effort_commands.source", value="gravity"),
                Parameter("external_wrench.frame", value="tip"),
                Parameter("collision.observer_gain", value=100.0),
            ]
        )
        estimates = harness.listen(WrenchStamped, "external_wrench", 10000)
        pushes = harness.publisher(WrenchStamped, "/sim_node/external_wrench")
        pushes.publish(wrench("flange", PUSH))
        received(harness, 1)
        end = round(DURATION * 1e9)
        assert harness.spin_until(lambda: estimates and stamp(estimates[-1]) >= end, timeout=600.0)
        settled = [m for m in estimates if round(SETTLED * 1e9) <= stamp(m) <= end]
        assert len(settled) > 100
        for msg in settled:
            assert msg.header.frame_id == "flange"
            f, m = msg.wrench.force, msg.wrench.torque
            force_error = np.linalg.norm(np.array([f.x, f.y, f.z]) - PUSH)
            torque_error = np.linalg.norm([m.x, m.y, m.z])  # N m: none pushed
            assert force_error <= 0.05 * 20.0 and torque_error <= 0.05 * 20.0 * 0.1, (stamp(msg), f, m)
        moved = np.abs(harness.node.simulation.arm.q - POSE).max()
        assert 1e-3 < moved < 0.3, moved  # the arm gave way, far from its limits
