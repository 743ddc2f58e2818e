"""id_node's wrist force/torque sensor in-process: readings of a 2 kg tool on the flange
(with a bias, the node told 0.5 kg) at rest in three poses; ~/estimate_ft_load gives the
bias, 2 kg and the CoM, uses the bias and sets payload.mass and .com (ft_sensor.apply_load);
then a known push reads as it was on ft_contact_wrench, in the sensor's axes and the base's,
stamped like the reading; a reading not finite, or in another link's frame (header.frame_id),
is dropped and counted, one in the sensor link's frame taken; a sensor link not on the last link
stops the start with one line."""

import numpy as np
import pytest
from geometry_msgs.msg import WrenchStamped
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from irb140_dynamics.core import RigidBody, irb140
from irb140_dynamics.core.ft_sensor.contact import tool_wrench
from irb140_dynamics.nodes.id_node.node import IdNode

from ..support.ros_harness import running

TOOL = RigidBody(2.0, (0.02, -0.01, 0.1))
TRUE_ARM = irb140().with_payload(TOOL)
BIAS = np.array([2.0, -1.0, 3.0, 0.2, -0.1, 0.05])
POSES = [[0.3, -0.4, 0.5, *wrist] for wrist in ([0.0, 0.5, 0.0], [1.2, -0.8, 0.5], [-0.7, 1.2, 1.7])]
OVERRIDES = [
    Parameter("payload.mass", value=0.5),
    Parameter("ft_sensor.link", value="flange"),
    Parameter("ft_sensor.apply_load", value=True),
]


def stamped(msg, t: float):
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int(round((t % 1) * 1e9))
    return msg


def send(harness, t: float, q, qd, wrench, frame_id: str = "") -> None:
    """A joint state, taken, then a reading at the same stamp in ``frame_id``."""
    names, counts = harness.node.settings.model.joint_names, harness.node.counts
    received = counts["joint_states.received"]
    harness.joint_states.publish(stamped(JointState(name=list(names), position=list(q), velocity=list(qd)), t))
    assert harness.spin_until(lambda: counts["joint_states.received"] > received), "joint state not taken"
    reading, count = stamped(WrenchStamped(), t), len(harness.contacts) + len(harness.node.counts)
    reading.header.frame_id = frame_id
    f, m = reading.wrench.force, reading.wrench.torque
    f.x, f.y, f.z, m.x, m.y, m.z = (float(x) for x in wrench)
    harness.readings.publish(reading)
    assert harness.spin_until(lambda: len(harness.contacts) + len(harness.node.counts) > count), "reading not taken"


def read(msg) -> np.ndarray:
    f, m = msg.wrench.force, msg.wrench.torque
    return np.array([f.x, f.y, f.z, m.x, m.y, m.z])


def test_the_load_is_estimated_from_rests_and_a_push_reads_as_it_was():
    with running(IdNode, parameter_overrides=OVERRIDES) as harness:
        harness.contacts = harness.listen(WrenchStamped, "ft_contact_wrench", 100)
        harness.joint_states = harness.publisher(JointState, "joint_states")
        harness.readings = harness.publisher(WrenchStamped, "ft_wrench")
        assert harness.spin_until(lambda: harness.node.settings is not None), "no model"
        zero = np.zeros(6)
        t = 10.0
        for q in POSES:  # 0.6 s at rest, then a moment of motion ends the rest
            reading = tool_wrench(TRUE_ARM, q, zero, zero)[0] + BIAS
            for k in range(7):
                send(harness, t + 0.1 * k, q, zero, reading)
            send(harness, t + 0.65, q, np.full(6, 0.5), reading)
            t += 2.0
        send(harness, t, q, zero, [np.nan] * 6)
        assert harness.node.counts["ft_wrench.dropped_not_finite"] == 1
        send(harness, t, q, zero, reading, frame_id="link_6")  # the sensor's link is the flange
        assert harness.node.counts["ft_wrench.dropped_wrong_frame"] == 1
        client = harness.probe.create_client(Trigger, "/id_node/estimate_ft_load")
        assert client.wait_for_service(timeout_sec=10.0)
        reply = harness.call(lambda: client.call_async(Trigger.Request()))
        assert reply.success, reply.message
        assert reply.message.startswith("bias (2.000, -1.000, 3.000, 0.200, -0.100, 0.050) N, N m; tool 2.000 +- ")
        assert "; 3 poses; condition " in reply.message
        assert "applied: the bias, payload.mass, payload.com" in reply.message
        harness.settle()
        payload = harness.node.model.payload
        assert abs(payload.mass - 2.0) < 1e-6 and np.allclose(payload.com, TOOL.com, atol=1e-6)
        push = np.array([5.0, -20.0, 3.0, 0.5, 0.2, -0.1])  # on the tool, sensor axes, about its origin
        q, t = POSES[1], t + 1.0
        send(harness, t, q, zero, tool_wrench(TRUE_ARM, q, zero, zero)[0] + BIAS + push, frame_id="flange")
        last = harness.contacts[-1]
        assert last.header.frame_id == "flange" and (last.header.stamp.sec, last.header.stamp.nanosec) == (17, 0)
        np.testing.assert_allclose(read(last), push, atol=1e-6)
        refused = harness.set_parameters([Parameter("ft_contact_wrench.frame", value="tool")])[0]
        assert not refused.successful and refused.reason.startswith("ft_contact_wrench.frame: must be one of")
        assert harness.set_parameters([Parameter("ft_contact_wrench.frame", value="base")])[0].successful
        send(harness, t + 0.1, q, zero, tool_wrench(TRUE_ARM, q, zero, zero)[0] + BIAS + push)
        _, R = tool_wrench(TRUE_ARM, q, zero, zero)
        assert harness.contacts[-1].header.frame_id == "base_link"
        np.testing.assert_allclose(read(harness.contacts[-1]), np.concatenate([R @ push[:3], R @ push[3:]]), atol=1e-6)


def test_a_sensor_link_before_the_last_joint_stops_the_start():
    refused = (
        r"^ft_sensor.link: 'link_3' is moved by joint joint_3, not by joint_6 that carries the flange: the sensor must"
    )
    with (
        pytest.raises(ValueError, match=refused),
        running(IdNode, parameter_overrides=[Parameter("ft_sensor.link", value="link_3")]),
    ):
        pass
