"""id_node in-process for the collision tests: the fixture and a joint-state feeder."""

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool

from irb140_dynamics.nodes.id_node.node import IdNode

from .ros_harness import running

NAMES = [f"joint_{i}" for i in range(1, 7)]
GAIN = 100.0  # 1/s
THRESHOLD = 10.0  # N m, joint_2's (the others: off)
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


@pytest.fixture
def node():
    overrides = [
        Parameter("collision.observer_gain", value=GAIN),
        Parameter("joint_2.collision_threshold", value=THRESHOLD),
    ]
    with running(IdNode, parameter_overrides=overrides) as harness:
        harness.external = harness.listen(JointState, "external_torques")
        harness.gravity = harness.listen(JointState, "gravity_torques")
        harness.collision = harness.listen(Bool, "collision", LATCHED)
        harness.diagnostics = harness.listen(DiagnosticArray, "/diagnostics")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        yield harness


def stamped(msg: JointState, t: float) -> JointState:
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int(round((t % 1) * 1e9))
    return msg


def state(t, q, qd, effort=None):
    msg = JointState(name=NAMES, position=list(map(float, q)), velocity=list(map(float, qd)))
    if effort is not None:
        msg.effort = list(map(float, effort))
    return stamped(msg, t)


def send(harness, msg: JointState, observed=True):
    """One joint state; waits for its torques (and its external torques when ``observed``):
    the residual, or None."""
    g, e = len(harness.gravity), len(harness.external)
    harness.joint_states.publish(msg)
    assert harness.spin_until(lambda: len(harness.gravity) > g)
    if observed:
        assert harness.spin_until(lambda: len(harness.external) > e)
        return np.array(harness.external[-1].effort)
    return None


def feed(harness, t, q, qd, effort=None, observed=True):
    """One joint state of the model's joints in order (see send)."""
    return send(harness, state(t, q, qd, effort), observed and effort is not None)


def collision_statuses(harness, after=None) -> list:
    """The id_node collision statuses received (of diagnostics stamped at or after ``after``, a Time)."""
    return [
        s
        for d in harness.diagnostics
        for s in d.status
        if s.name.endswith(": collision")
        and (after is None or (d.header.stamp.sec, d.header.stamp.nanosec) >= after.seconds_nanoseconds())
    ]
