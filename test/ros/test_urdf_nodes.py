"""The nodes with model.source robot_description, in-process: the URDF as a parameter, a
file or on the topic (before and after the node starts), gravity torques as Pinocchio's;
a bad URDF fails startup in one line, or is refused at run time keeping the model."""

from contextlib import contextmanager

import numpy as np
import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from std_srvs.srv import Trigger

from irb140_dynamics.core import RigidBody, gravity
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode
from irb140_dynamics.ros.parameters.arm import DESCRIPTION_QOS

from ..core.test_urdf_refusals import ARM, REFUSED
from ..support.paths import URDF_DATA
from ..support.ros_harness import Harness, built, running
from ..support.urdf_support import ARMS, arm_text, expected_gravity

PAYLOAD = RigidBody(2.5, (0.01, 0.02, 0.05), (0.01, 0.01, 0.01, 0.0, 0.0, 0.0))


def from_urdf(tip=None, **values):
    overrides = [Parameter("model.source", value="robot_description")]
    if tip:
        overrides.append(Parameter("model.tip_link", value=tip))
    return overrides + [Parameter(name.replace("__", "."), value=value) for name, value in values.items()]


def gravity_of(harness, names, q):
    """Publish one joint state; the gravity_torques message it yields."""
    if "gravity_torques" not in harness.received:
        harness.listen(JointState, "gravity_torques")
        harness.joint_states = harness.publisher(JointState, "joint_states")
    inbox = harness.received["gravity_torques"]
    count = len(inbox)
    harness.joint_states.publish(JointState(name=list(names), position=[float(x) for x in q]))
    assert harness.spin_until(lambda: len(inbox) > count), "no gravity torques"
    return inbox[-1]


def check_gravity(harness, text, tip, payload=None, seed=0):
    names = harness.node.settings.model.joint_names
    q = np.random.default_rng(seed).uniform(-2.0, 2.0, len(names))
    msg = gravity_of(harness, names, q)
    assert tuple(msg.name) == names
    np.testing.assert_allclose(msg.effort, expected_gravity(text, tip, q, payload), rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("arm", list(ARMS))
def test_robot_description_parameter(arm):
    text, tip = arm_text(arm), ARMS[arm][1]
    with running(IdNode, parameter_overrides=from_urdf(tip, robot_description=text)) as harness:
        check_gravity(harness, text, tip)


def test_urdf_file_parameter_and_payload_on_the_tip_link():
    text, tip = arm_text("panda"), ARMS["panda"][1]
    payload = [
        Parameter("payload.mass", value=PAYLOAD.mass),
        Parameter("payload.com", value=list(PAYLOAD.com)),
        Parameter("payload.inertia", value=list(PAYLOAD.inertia)),
    ]
    overrides = from_urdf(tip, model__urdf_file=str(URDF_DATA / "panda.urdf")) + payload
    with running(IdNode, parameter_overrides=overrides) as harness:
        check_gravity(harness, text, tip, PAYLOAD)


@contextmanager
def node_and_description_publisher(make_node, overrides, text_before=None):
    """The node, and a transient-local publisher of robot_description (publishing
    ``text_before`` before the node exists, when given)."""
    context = Context()
    rclpy.init(context=context)
    publisher_node = Node("description_publisher", context=context)
    publisher = publisher_node.create_publisher(String, "robot_description", DESCRIPTION_QOS)
    harness = None
    try:
        if text_before is not None:
            publisher.publish(String(data=text_before))
        harness = Harness(context, built(make_node, context=context, parameter_overrides=overrides))
        harness.executor.add_node(publisher_node)
        harness.description = publisher
        yield harness
    finally:
        if harness is not None:
            harness.close()
        publisher_node.destroy_node()
        rclpy.try_shutdown(context=context)


def description_source(node):
    """What keeps the node's URDF (and counts those refused)."""
    return node.parameters


def test_topic_published_before_the_node_starts():
    text, tip = arm_text("ur5"), ARMS["ur5"][1]
    with node_and_description_publisher(IdNode, from_urdf(tip), text_before=text) as harness:
        assert harness.spin_until(lambda: harness.node.settings is not None)
        check_gravity(harness, text, tip)


def test_topic_after_start_waits_then_swaps_whole_models_and_refuses_bad_ones():
    ur5, tip = arm_text("ur5"), ARMS["ur5"][1]
    with node_and_description_publisher(IdNode, from_urdf(tip)) as harness:
        node = harness.node
        assert node.settings is None and node.settings is None
        inbox = harness.listen(JointState, "gravity_torques")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        harness.joint_states.publish(JointState(name=["shoulder_pan_joint"], position=[0.0]))
        assert harness.spin_until(lambda: node.counts["joint_states.no_model_yet"] == 1)
        harness.spin_for(0.2)
        assert not inbox, "published torques without a model"

        harness.description.publish(String(data=ur5))
        assert harness.spin_until(lambda: node.settings is not None)
        check_gravity(harness, ur5, tip)

        kept = node.settings
        harness.description.publish(String(data=ur5.replace('"tool0"', '"tool1"')))  # no tip link: refused
        assert harness.spin_until(lambda: description_source(node).refused == 1)
        assert node.settings is kept
        check_gravity(harness, ur5, tip, seed=1)

        heavier = ur5.replace('<mass value="8.393"/>', '<mass value="12.0"/>').replace("elbow_joint", "elbow")
        harness.description.publish(String(data=heavier))
        assert harness.spin_until(lambda: node.settings is not kept)
        assert node.settings.model.joint_names[2] == "elbow"
        check_gravity(harness, heavier, tip, seed=2)


def test_each_bad_urdf_on_the_topic_is_refused_for_its_reason_and_the_model_kept():
    with node_and_description_publisher(IdNode, from_urdf("l2")) as harness:
        harness.description.publish(String(data=ARM))
        assert harness.spin_until(lambda: harness.node.settings is not None)
        kept, source = harness.node.settings, description_source(harness.node)
        bad = {
            name: (text, message)
            for name, (text, ends, message) in REFUSED.items()
            if not ends and name != "several_leaves"
        }  # with tip_link l2, several leaves are fine
        for count, (name, (text, message)) in enumerate(bad.items(), start=1):
            harness.description.publish(String(data=text))
            assert harness.spin_until(lambda: source.refused == count), name
            assert source.last_refusal.startswith("robot_description topic: ") and message in source.last_refusal, name
        assert harness.node.settings is kept
        q = [0.3, -0.7]
        np.testing.assert_allclose(gravity_of(harness, ["j1", "j2"], q).effort, gravity(kept.model, q), rtol=1e-15)


@pytest.mark.parametrize("text, ends, message", list(REFUSED.values()), ids=list(REFUSED))
def test_bad_urdf_stops_startup_with_one_line(text, ends, message):
    overrides = from_urdf(ends.get("tip_link"), robot_description=text)
    if "base_link" in ends:
        overrides.append(Parameter("model.base_link", value=ends["base_link"]))
    with pytest.raises(ValueError) as refused, running(IdNode, parameter_overrides=overrides):
        pass
    assert str(refused.value).startswith("robot_description parameter: ")
    assert message in str(refused.value) and "\n" not in str(refused.value)


def test_bad_parameter_is_refused_while_waiting():
    with node_and_description_publisher(IdNode, from_urdf("tool0")) as harness:
        [result] = harness.set_parameters([Parameter("payload.com", value=[0.0, 1.0])])
        assert not result.successful and "payload.com" in result.reason
        [result] = harness.set_parameters([Parameter("payload.mass", value=3.0)])
        assert result.successful
        harness.description.publish(String(data=arm_text("ur5")))
        assert harness.spin_until(lambda: harness.node.settings is not None)
        assert harness.node.settings.model.payload.mass == 3.0


def test_payload_check_node_waits_then_checks_on_the_urdf_model():
    text, tip = arm_text("ur5"), ARMS["ur5"][1]
    overrides = from_urdf(tip) + [Parameter("payload.mass", value=5.0), Parameter("diagnostics.period", value=0.0)]
    with node_and_description_publisher(PayloadCheckNode, overrides) as harness:
        client = harness.probe.create_client(Trigger, "/payload_check_node/check")
        assert client.wait_for_service(timeout_sec=10)
        reply = harness.call(lambda: client.call_async(Trigger.Request()))
        assert not reply.success and "no model yet" in reply.message
        states = harness.publisher(JointState, "joint_states")  # before the model: kept for it
        names = [
            f"{part}_joint" for part in ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
        ]
        states.publish(JointState(name=names, position=[0.1, -0.8, 0.9, 0.2, 0.3, 0.4], velocity=[0.0] * 6))
        assert harness.spin_until(lambda: harness.node.counts["joint_states.no_model_yet"] == 1)
        harness.description.publish(String(data=text))
        assert harness.spin_until(lambda: harness.node.settings is not None)
        reply = harness.call(lambda: client.call_async(Trigger.Request()))
        assert "shoulder_lift_joint" in reply.message and "no joint_states received yet" not in reply.message
        result, _ = harness.node.check()
        assert result.limit.tolist() == [150.0, 150.0, 150.0, 28.0, 28.0, 28.0]  # the URDF's effort limits
        assert result.q.tolist() == [0.1, -0.8, 0.9, 0.2, 0.3, 0.4]  # the joint state sent before the model


def test_per_joint_node_parameters_are_declared_when_the_urdf_comes():
    overrides = from_urdf("tool0") + [Parameter("elbow_joint.collision_threshold", value=5.0)]
    with node_and_description_publisher(IdNode, overrides) as harness:
        assert not harness.node.has_parameter("elbow_joint.collision_threshold")
        harness.description.publish(String(data=arm_text("ur5")))
        assert harness.spin_until(lambda: harness.node.settings is not None)
        assert harness.node.get_parameter("elbow_joint.collision_threshold").value == 5.0
        assert harness.node.settings.collision.thresholds.tolist() == [0.0, 0.0, 5.0, 0.0, 0.0, 0.0]
        [result] = harness.set_parameters([Parameter("wrist_1_joint.collision_threshold", value=2.0)])
        assert result.successful and harness.node.settings.collision.thresholds[3] == 2.0
