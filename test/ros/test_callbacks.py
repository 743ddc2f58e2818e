"""No input leaves a callback with an exception: what cannot give finite torques is dropped,
counted per topic, and the node goes on."""

import math

import numpy as np
import pytest
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from irb140_dynamics.core import RigidBody, gravity, irb140, rnea
from irb140_dynamics.nodes.id_node import node as id_module
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.payload_check_node import node as payload_module
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode

from ..support.ros_harness import running

NAMES = [f"joint_{i}" for i in range(1, 7)]
Q = [0.1, -0.8, 1.0, 0.2, 0.5, 0.0]
DIFFERENTIATE = [Parameter("acceleration.mode", value="differentiate")]


def joint_state(q, qd=(), sec=1, nanosec=0, names=NAMES):
    msg = JointState(name=list(names), position=[float(x) for x in q], velocity=[float(x) for x in qd])
    msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
    return msg


def reference(q, qd=(), qdd=()):
    point = JointTrajectoryPoint(positions=list(q), velocities=list(qd), accelerations=list(qdd))
    return JointTrajectory(joint_names=NAMES, points=[point])


@pytest.fixture
def differentiating():
    with running(IdNode, parameter_overrides=DIFFERENTIATE) as harness:
        harness.feedforward = harness.listen(JointState, "feedforward_torques")
        harness.gravity = harness.listen(JointState, "gravity_torques")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        yield harness


def publish_and_count(harness, msg, topic_count: str, count: int = 1) -> None:
    harness.joint_states.publish(msg)
    assert harness.spin_until(lambda: harness.node.counts[topic_count] >= count)


@pytest.mark.parametrize("jump", [1e300, 1e200, 1e160])
def test_an_absurd_velocity_jump_is_dropped_and_the_filter_starts_afresh(differentiating, jump):
    """Two states 1 ns apart, velocities 0 then ``jump``: the differentiated qdd (or the
    torques it gives) is not finite. Reproduction of the issue: the node died there."""
    node = differentiating
    publish_and_count(node, joint_state(Q, [0.0] * 6, sec=1, nanosec=0), "torques.published")
    node.joint_states.publish(joint_state(Q, [jump] * 6, sec=1, nanosec=1))
    assert node.spin_until(lambda: node.node.counts["joint_states.dropped"] == 1)
    kinds = {key for key in node.node.counts if key.startswith("joint_states.dropped_")}
    assert kinds <= {"joint_states.dropped_not_finite_acceleration", "joint_states.dropped_non_finite_torques"}
    assert node.node.counts["torques.published"] == 1
    # alive, and the filter restarted: the next state gives qdd = 0 (no memory of the jump)
    publish_and_count(node, joint_state(Q, [0.3] * 6, sec=1, nanosec=2_000_000), "torques.published", 2)
    assert node.spin_until(lambda: len(node.feedforward) == 2)
    np.testing.assert_allclose(
        node.feedforward[-1].effort, rnea(irb140(), Q, [0.3] * 6, np.zeros(6)), rtol=1e-12, atol=1e-12
    )


def test_a_huge_finite_acceleration_still_gives_the_core_torques(differentiating):
    """1e10 rad/s within 1 ns is absurd but finite all through: the torques are the core's
    at the filtered qdd, whatever it is (nothing to drop)."""
    node = differentiating
    publish_and_count(node, joint_state(Q, [0.0] * 6, sec=1, nanosec=0), "torques.published")
    publish_and_count(node, joint_state(Q, [1e10] * 6, sec=1, nanosec=1), "torques.published", 2)
    assert node.spin_until(lambda: len(node.feedforward) == 2)
    qdd = node.node.stream.differentiator.qdd
    assert all(map(math.isfinite, qdd)) and max(qdd) > 1e10
    np.testing.assert_allclose(node.feedforward[-1].effort, rnea(irb140(), Q, [1e10] * 6, qdd), rtol=1e-12)


@pytest.fixture
def id_node():
    with running(IdNode) as harness:
        harness.feedforward = harness.listen(JointState, "feedforward_torques")
        harness.gravity = harness.listen(JointState, "gravity_torques")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        harness.reference = harness.publisher(JointTrajectory, "/id_node/reference")
        yield harness


def test_an_absurd_reference_is_refused_on_arrival_and_counted_as_a_reference(id_node):
    node = id_node
    node.reference.publish(reference(Q, [1e200] * 6))
    assert node.spin_until(lambda: node.node.counts["reference.dropped_non_finite_torques"] == 1)
    assert node.node.stream.tracker.trajectory is None
    # the joint states are unaffected: gravity and feed-forward torques at the measured state
    publish_and_count(node, joint_state(Q), "torques.published")
    assert node.spin_until(lambda: node.feedforward and node.gravity)
    np.testing.assert_allclose(node.gravity[-1].effort, gravity(irb140(), Q), rtol=1e-12, atol=1e-12)
    assert node.node.counts["joint_states.dropped"] == 0


def test_a_held_reference_the_new_model_cannot_take_is_let_go(id_node):
    """qd = 3e153 gives finite torques (about 1e308) with the bare arm, none with 1e6 kg."""
    node = id_node
    qd = [0.0, 0.0, 0.0, 0.0, 0.0, 3e153]
    assert math.isfinite(max(abs(rnea(irb140(), Q, qd, np.zeros(6)))))
    node.reference.publish(reference(Q, qd))
    assert node.spin_until(lambda: node.node.stream.tracker.trajectory is not None)
    heavy = RigidBody(1e6, (0.5, 0.5, 0.5), (1e6, 1e6, 1e6, 0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="not finite"):  # the core refuses such torques
        rnea(irb140(payload=heavy), Q, qd, np.zeros(6))
    changes = [
        Parameter("payload.mass", value=heavy.mass),
        Parameter("payload.com", value=list(heavy.com)),
        Parameter("payload.inertia", value=list(heavy.inertia)),
    ]
    assert node.set_parameters_atomically(changes).successful
    assert node.node.stream.tracker.trajectory is None
    assert node.node.counts["reference.dropped_non_finite_torques"] == 1


def test_an_exception_of_ours_in_a_callback_is_counted_and_the_node_goes_on(id_node, monkeypatch):
    node = id_node

    def broken(*args):
        raise RuntimeError("a defect")

    monkeypatch.setattr(id_module, "read_joint_sample", broken)
    node.joint_states.publish(joint_state(Q))
    assert node.spin_until(lambda: node.node.counts["joint_states.errors"] == 1)
    monkeypatch.undo()
    publish_and_count(node, joint_state(Q), "torques.published")


@pytest.fixture
def payload_node():
    overrides = [Parameter("diagnostics.period", value=0.0)]
    with running(PayloadCheckNode, parameter_overrides=overrides) as harness:
        harness.joint_states = harness.publisher(JointState, "joint_states")
        harness.client = harness.probe.create_client(Trigger, "/payload_check_node/check")
        assert harness.client.wait_for_service(timeout_sec=10)
        yield harness


def check(harness):
    return harness.call(lambda: harness.client.call_async(Trigger.Request()))


def test_payload_check_drops_a_joint_state_without_finite_torques(payload_node):
    """Velocities 1e200: dropped as id_node drops it; the check keeps the state before."""
    node = payload_node
    node.joint_states.publish(joint_state(Q))
    assert node.spin_until(lambda: node.node.state is not None)
    node.joint_states.publish(joint_state(Q, [1e200] * 6))
    assert node.spin_until(lambda: node.node.counts["joint_states.dropped_non_finite_torques"] == 1)
    reply = check(node)
    assert reply.success, reply.message
    assert "nan" not in reply.message and reply.message.startswith("OK: ")
    assert list(node.node.state.q) == Q


def test_payload_check_answers_an_internal_error_and_goes_on(payload_node, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("a defect")

    monkeypatch.setattr(payload_module, "check_payload", broken)
    reply = check(payload_node)
    assert not reply.success and reply.message == "UNPROVEN: not checked: internal error RuntimeError: a defect"
    assert payload_node.node.counts["check.errors"] == 1
    monkeypatch.undo()
    assert check(payload_node).success


def test_nan_in_a_joint_the_model_does_not_have_is_not_its_concern(id_node):
    """Joints the model lacks are ignored entirely, values and all (README, Joint matching)."""
    node = id_node
    msg = joint_state(Q + [math.nan, math.inf], [0.0] * 6 + [math.nan, 0.0], names=NAMES + ["gripper", "tool"])
    publish_and_count(node, msg, "torques.published")
    assert node.spin_until(lambda: node.gravity)
    np.testing.assert_allclose(node.gravity[-1].effort, gravity(irb140(), Q), rtol=1e-12, atol=1e-12)
    assert node.node.counts["joint_states.dropped"] == 0
