"""id_node's momentum observer in-process: external_torques, the collision flag, /diagnostics."""

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool

from irb140_dynamics.core import RigidBody, gravity, irb140, rnea
from irb140_dynamics.id_node import IdNode

from .ros_harness import running
from .test_observer import fast_motion

NAMES = [f"joint_{i}" for i in range(1, 7)]
GAIN = 100.0
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


@pytest.fixture
def node():
    overrides = [Parameter("collision.observer_gain", value=GAIN), Parameter("joint_2.collision_threshold", value=10.0)]
    with running(IdNode, parameter_overrides=overrides) as harness:
        harness.external = harness.listen(JointState, "external_torques")
        harness.gravity = harness.listen(JointState, "gravity_torques")
        harness.collision = harness.listen(Bool, "collision", LATCHED)
        harness.diagnostics = harness.listen(DiagnosticArray, "/diagnostics")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        yield harness


def state(t, q, qd, effort=None):
    msg = JointState(name=NAMES, position=list(map(float, q)), velocity=list(map(float, qd)))
    if effort is not None:
        msg.effort = list(map(float, effort))
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int(round((t % 1) * 1e9))
    return msg


def feed(harness, t, q, qd, effort=None, observed=True):
    """One joint state; waits for its torques (and its external torques when it has efforts)."""
    g, e = len(harness.gravity), len(harness.external)
    harness.joint_states.publish(state(t, q, qd, effort))
    assert harness.spin_until(lambda: len(harness.gravity) > g)
    if effort is not None and observed:
        assert harness.spin_until(lambda: len(harness.external) > e)
        return np.array(harness.external[-1].effort)
    return None


def test_no_efforts_no_external_torques(node):
    for k in range(5):
        feed(node, 1 + k * 0.001, np.zeros(6), np.zeros(6))
    node.spin_for(0.1)
    assert node.external == []


def test_fast_motion_without_contact_stays_quiet(node):
    model = irb140()
    residuals, peak = [], 0.0
    for k in range(300):
        t = 1 + k * 0.001
        q, qd, qdd = fast_motion(t)
        tau = rnea(model, q, qd, qdd)
        peak = max(peak, np.abs(tau).max())
        residuals.append(feed(node, t, q, qd, tau))
    assert np.abs(residuals).max() < 0.01 * peak
    assert [m.data for m in node.collision] == [False]
    assert node.external[-1].name == NAMES


def test_step_on_joint_2_flags_a_collision_within_10_ms(node):
    model = irb140()
    q = np.array([0.0, -0.6, 0.9, 0.0, 0.4, 0.0])
    g = gravity(model, q)
    step = np.array([0.0, 20.0, 0.0, 0.0, 0.0, 0.0])
    assert node.spin_until(lambda: node.collision)  # the latched flag's topic matched (discovery done)
    flagged_at, r = None, None
    for k in range(120):
        t = 2 + k * 0.001
        pushed = t >= 2.05 - 1e-9
        r = feed(node, t, q, np.zeros(6), g - step if pushed else g)
        if flagged_at is None and len(node.collision) > 1 and node.collision[-1].data:
            flagged_at = t
    assert flagged_at is not None and flagged_at <= 2.05 + 0.010 + 1e-9
    assert abs(r[1] - 20.0) <= 1.0 and np.abs(r[[0, 2, 3, 4, 5]]).max() < 0.2
    assert node.spin_until(lambda: any(
        s.level == DiagnosticStatus.ERROR and "joint_2" in s.message for d in node.diagnostics for s in d.status
    ), timeout=3.0)
    for k in range(60):  # the push ends: the flag clears
        r = feed(node, 2.2 + k * 0.001, q, np.zeros(6), g)
    assert node.collision[-1].data is False


def test_unmodelled_payload_is_a_static_residual(node):
    model = irb140()
    q = np.array([0.3, -0.5, 0.7, 0.2, 0.8, 0.1])
    carrying = gravity(model.with_payload(RigidBody(2.0, (0.0, 0.0, 0.05))), q)
    for k in range(100):
        r = feed(node, 3 + k * 0.001, q, np.zeros(6), carrying)
    np.testing.assert_allclose(r, -(carrying - gravity(model, q)), atol=0.02)


def test_bad_efforts_reset_the_observer_and_torques_still_flow(node):
    q = np.zeros(6)
    g = gravity(irb140(), q)
    for k in range(20):
        feed(node, 1 + k * 0.001, q, np.zeros(6), g - 5.0)
    assert np.all(np.abs(node.external[-1].effort) > 1.0)
    external = len(node.external)
    feed(node, 1.021, q, np.zeros(6), [float("nan")] * 6, observed=False)  # torques still published
    node.spin_for(0.1)
    assert len(node.external) == external
    r = feed(node, 1.022, q, np.zeros(6), g - 5.0)
    assert np.all(r == 0.0)  # started again
