"""id_node following a whole ~/reference trajectory, computed-torque commands, the hold
position without a reference, and ~/tracking_error (in-process)."""

from contextlib import contextmanager

import numpy as np
import pytest
from builtin_interfaces.msg import Duration
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from irb140_dynamics.core import irb140, rnea
from irb140_dynamics.core.trajectories.reference import computed_torque
from irb140_dynamics.nodes.id_node.node import IdNode

from ..support.ros_harness import running

NAMES = [f"joint_{i}" for i in range(1, 7)]
A = [0.1, -0.5, 0.6, 0.0, 0.3, 0.0]
B = [0.4, -0.2, 0.9, 0.5, -0.3, 0.8]
KP, KD = np.full(6, 400.0), np.full(6, 40.0)  # the defaults


@contextmanager
def tracking(*overrides: Parameter):
    """id_node in computed-torque mode (and ``overrides``), with the probe's topics."""
    defaults = [
        Parameter("effort_commands.enabled", value=True),
        Parameter("effort_commands.source", value="computed_torque"),
        Parameter("reference_timeout", value=0.5),
    ]
    with running(IdNode, parameter_overrides=[*defaults, *overrides]) as harness:
        harness.feedforward = harness.listen(JointState, "feedforward_torques")
        harness.gravity = harness.listen(JointState, "gravity_torques")
        harness.commands = harness.listen(Float64MultiArray, "effort_commands")
        harness.tracking = harness.listen(JointState, "/id_node/tracking_error")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        harness.reference = harness.publisher(JointTrajectory, "/id_node/reference")
        yield harness


@pytest.fixture
def node():
    with tracking() as harness:
        yield harness


def send(harness, q, qd=(0.0,) * 6, tracking=False):
    """One joint state: (feed-forward, command) in reply (and its tracking error first)."""
    n, t = len(harness.commands), len(harness.tracking)
    harness.joint_states.publish(JointState(name=NAMES, position=list(q), velocity=list(qd)))
    assert harness.spin_until(lambda: len(harness.commands) > n and (not tracking or len(harness.tracking) > t))
    return np.array(harness.feedforward[-1].effort), np.array(harness.commands[-1].data)


def trajectory(points):
    """(time [s], q) pairs at rest as a JointTrajectory."""
    msg = JointTrajectory(joint_names=NAMES)
    for t, q in points:
        sec, nanosec = divmod(int(round(t * 1e9)), 10**9)
        msg.points.append(
            JointTrajectoryPoint(
                positions=list(q),
                velocities=[0.0] * 6,
                accelerations=[0.0] * 6,
                time_from_start=Duration(sec=sec, nanosec=nanosec),
            )
        )
    return msg


def follow(harness, msg):
    harness.reference.publish(msg)
    assert harness.spin_until(lambda: harness.node.stream.tracker.trajectory is not None)


def elapsed(harness) -> float:
    """s on the node's clock since the reference in force started."""
    return harness.node.get_clock().now().nanoseconds * 1e-9 - harness.node.stream.tracker.start


def test_a_trajectory_is_followed_in_time_held_at_its_end_then_let_go():
    """Waits on the node's clock (past the end, past the timeout), not on sleeps: a stall of
    the machine shorter than the 2 s reference_timeout changes nothing."""
    model, zeros = irb140(), np.zeros(6)
    with tracking(Parameter("reference_timeout", value=2.0)) as node:
        follow(node, trajectory([(0.0, A), (0.3, B)]))
        ff, _ = send(node, A, tracking=True)
        q_ref = np.add(A, node.tracking[-1].position)  # on the way from A to B (or at B)
        moving = np.subtract(B, A) != 0.0
        w = (q_ref - A)[moving] / np.subtract(B, A)[moving]
        assert 0.0 <= w[0] <= 1.0 and np.allclose(w, w[0], atol=1e-12)
        np.testing.assert_allclose(ff, rnea(model, q_ref, zeros, zeros), rtol=1e-9, atol=1e-9)
        assert node.spin_until(lambda: elapsed(node) > 0.3)  # past the last point: it is held
        ff, _ = send(node, A, tracking=True)
        assert elapsed(node) < 0.3 + 2.0, "the machine stalled for the whole reference_timeout"
        np.testing.assert_allclose(ff, rnea(model, B, zeros, zeros), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(node.tracking[-1].position, np.subtract(B, A), atol=1e-12)
        assert node.spin_until(lambda: elapsed(node) > 0.3 + 2.0)  # let go: the measured state
        ff, _ = send(node, A)
    np.testing.assert_allclose(ff, rnea(model, A, zeros, zeros), rtol=1e-12, atol=1e-12)


def test_computed_torque_commands_toward_the_reference(node):
    model = irb140()
    follow(node, trajectory([(0.0, B)]))
    q, qd = np.array(A), np.array([0.1, -0.2, 0.3, 0.0, 0.1, -0.1])
    _, command = send(node, q, qd)
    expected = computed_torque(model, q, qd, B, np.zeros(6), np.zeros(6), KP, KD)
    np.testing.assert_allclose(command, expected, rtol=1e-12, atol=1e-12)


def test_without_a_reference_it_holds_the_first_measured_position(node):
    model = irb140()
    send(node, A)
    q2 = np.add(A, 0.05)
    _, command = send(node, q2)
    np.testing.assert_allclose(
        command, computed_torque(model, q2, np.zeros(6), A, np.zeros(6), None, KP, KD), rtol=1e-12, atol=1e-12
    )


def test_gains_are_live_parameters(node):
    [refused] = node.set_parameters([Parameter("joint_2.kp", value=-1.0)])
    assert not refused.successful
    [accepted] = node.set_parameters([Parameter("joint_2.kp", value=100.0)])
    assert accepted.successful
    follow(node, trajectory([(0.0, B)]))
    _, command = send(node, A)
    kp = KP.copy()
    kp[1] = 100.0
    np.testing.assert_allclose(
        command, computed_torque(irb140(), A, np.zeros(6), B, np.zeros(6), np.zeros(6), kp, KD), rtol=1e-12, atol=1e-12
    )


@pytest.mark.parametrize("times", [[0.0, -1.0], [1.0, 0.5]])
def test_a_trajectory_going_back_in_time_is_refused(node, times):
    node.reference.publish(trajectory([(times[0], A), (times[1], B)]))
    assert node.spin_until(lambda: node.node.counts["reference.dropped"] >= 1)
    assert node.node.stream.tracker.trajectory is None
