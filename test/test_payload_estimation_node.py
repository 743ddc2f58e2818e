"""payload_check_node's ~/estimate_payload and ~/clear_samples in-process."""

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from irb140_dynamics.core import gravity, irb140
from irb140_dynamics.payload_check_node import PayloadCheckNode

from .ros_harness import running
from .test_payload_estimation import PAYLOAD, WRIST_POSES

NAMES = [f"joint_{i}" for i in range(1, 7)]
PER_POSE = 80  # joint states at 1 kHz stamps: 80 ms of rest per pose


@pytest.fixture
def node():
    overrides = [
        Parameter("diagnostics.period", value=0.0),
        Parameter("estimation.rest_time", value=0.05),
        Parameter("estimation.apply", value=True),
    ]
    with running(PayloadCheckNode, parameter_overrides=overrides) as harness:
        harness.diagnostics = harness.listen(DiagnosticArray, "/diagnostics")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        harness.clients = {}
        for name in ("estimate_payload", "clear_samples", "check"):
            client = harness.probe.create_client(Trigger, f"/payload_check_node/{name}")
            assert client.wait_for_service(timeout_sec=10)
            harness.clients[name] = client
        harness.t = 1.0
        yield harness


def call(harness, name):
    return harness.call(lambda: harness.clients[name].call_async(Trigger.Request()))


def send(harness, q, qd, effort=None):
    harness.t += 0.001
    msg = JointState(name=NAMES, position=list(map(float, q)), velocity=list(map(float, qd)))
    if effort is not None:
        msg.effort = list(map(float, effort))
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(harness.t), int(round((harness.t % 1) * 1e9))
    before = harness.node._state
    harness.joint_states.publish(msg)
    assert harness.spin_until(lambda: harness.node._state is not before)


def rest_in(harness, poses, rng, with_effort=True):
    """The arm stops in each pose; efforts hold it and the payload, noise 1 % of peak."""
    true = irb140(payload=PAYLOAD)
    peak = np.max(np.abs([gravity(true, q) for q in poses]), axis=0)
    for q in poses:
        for _ in range(PER_POSE):
            effort = gravity(true, q) + rng.normal(0.0, 0.01 * peak) if with_effort else None
            send(harness, q, np.zeros(6), effort)
        send(harness, q, np.full(6, 0.5), effort)  # and moves on


def test_estimate_from_four_wrist_poses_is_applied(node):
    rest_in(node, WRIST_POSES, np.random.default_rng(0))
    reply = call(node, "estimate_payload")
    assert reply.success, reply.message
    mass = node.node.get_parameter("payload.mass").value
    com = node.node.get_parameter("payload.com").value
    assert mass == pytest.approx(PAYLOAD.mass, rel=0.02)
    assert np.linalg.norm(np.subtract(com, PAYLOAD.com)) < 0.005
    assert "4 poses" in reply.message and "applied" in reply.message
    node.settle()  # the new payload's workspace analysis runs off the executor
    assert f"payload {mass:.3f} kg" in call(node, "check").message  # the next check uses it
    statuses = {s.name: s for s in node.diagnostics[-1].status}
    assert "4 rest samples" in statuses["payload_check_node: payload estimation"].message


def test_two_poses_are_refused_and_nothing_applied(node):
    rest_in(node, WRIST_POSES[:2], np.random.default_rng(1))
    reply = call(node, "estimate_payload")
    assert not reply.success and "at least 3" in reply.message
    assert node.node.get_parameter("payload.mass").value == 0.0


def test_poses_differing_in_joint_1_only_are_refused(node):
    rest_in(node, [[a, -0.4, 0.5, 0.0, 0.3, 0.0] for a in (0.0, 0.8, 1.6, 2.4)], np.random.default_rng(2))
    reply = call(node, "estimate_payload")
    assert not reply.success and "too similar" in reply.message


def test_without_efforts_it_says_so(node):
    rest_in(node, WRIST_POSES, np.random.default_rng(3), with_effort=False)
    reply = call(node, "estimate_payload")
    assert not reply.success and "no effort" in reply.message


def test_clear_samples_forgets(node):
    rest_in(node, WRIST_POSES[:3], np.random.default_rng(4))
    assert call(node, "clear_samples").message == "forgot 3 rest samples"
    assert "at least 3" in call(node, "estimate_payload").message


def test_estimate_without_apply_leaves_the_payload(node):
    [result] = node.set_parameters([Parameter("estimation.apply", value=False)])
    assert result.successful
    rest_in(node, WRIST_POSES, np.random.default_rng(5))
    reply = call(node, "estimate_payload")
    assert reply.success and "applied" not in reply.message
    assert node.node.get_parameter("payload.mass").value == 0.0
