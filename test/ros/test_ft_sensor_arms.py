"""id_node's wrist force/torque sensor on an arm of a URDF (UR5, model.source
robot_description, the sensor on tool0): a 3 kg tool's load estimated from rests in three
poses streamed with zero velocities and no motion between them (a driver's), applied to
payload.mass and .com; a payload.link that would take the flange off the sensor's link is
refused in one line, the sensor staying on. Readings come from a best-effort publisher
(sensor-data QoS, as force/torque drivers publish): a reliable-only subscription would hear
nothing."""

import numpy as np
from geometry_msgs.msg import WrenchStamped
from rclpy.parameter import Parameter
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from irb140_dynamics.core import RigidBody
from irb140_dynamics.core.ft_sensor.contact import sensor_mount, tool_wrench
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.nodes.id_node.node import IdNode

from ..support.paths import URDF_DATA
from ..support.ros_harness import running
from .test_ft_sensor_node import read, send

UR5 = (URDF_DATA / "ur5.urdf").read_text()
TOOL = RigidBody(3.0, (0.01, 0.02, 0.05))
POSES = [[0.3, -0.4, 0.5, *wrist] for wrist in ([0.0, 0.5, 0.0], [1.2, -0.8, 0.5], [-0.7, 1.2, 1.7])]
OVERRIDES = [
    Parameter("model.source", value="robot_description"),
    Parameter("robot_description", value=UR5),
    Parameter("payload.mass", value=0.5),
    Parameter("ft_sensor.link", value="tool0"),
    Parameter("ft_sensor.apply_load", value=True),
]


def test_ur5_tool_estimated_from_rests_without_motion_between_them_and_a_flange_off_the_sensor_refused():
    loaded = load_urdf(UR5)
    with running(IdNode, parameter_overrides=OVERRIDES) as harness:
        harness.contacts = harness.listen(WrenchStamped, "ft_contact_wrench", 100)
        harness.joint_states = harness.publisher(JointState, "joint_states")
        harness.readings = harness.publisher(WrenchStamped, "ft_wrench", qos_profile_sensor_data)
        true_arm = harness.node.model.with_payload(TOOL)
        mount = sensor_mount(true_arm, "tool0", loaded.carried)
        zero = np.zeros(6)
        for i, q in enumerate(POSES):  # 0.7 s at each pose, qd = 0 throughout
            for k in range(8):
                send(harness, 10.0 + i + 0.1 * k, q, zero, tool_wrench(true_arm, q, zero, zero, mount)[0])
        client = harness.probe.create_client(Trigger, "/id_node/estimate_ft_load")
        assert client.wait_for_service(timeout_sec=10.0)
        reply = harness.call(lambda: client.call_async(Trigger.Request()))
        assert reply.success, reply.message
        assert "; 3 poses; " in reply.message and reply.message.endswith("applied: the bias, payload.mass, payload.com")
        harness.settle()
        payload = harness.node.model.payload
        assert abs(payload.mass - TOOL.mass) < 1e-9 and np.allclose(payload.com, TOOL.com, atol=1e-9)
        [refused] = harness.set_parameters([Parameter("payload.link", value="forearm_link")])
        assert not refused.successful and "\n" not in refused.reason
        assert refused.reason.startswith("ft_sensor.link: 'tool0' is moved by joint wrist_3_joint, not by elbow_joint")
        assert harness.node.model.payload.mass == payload.mass and harness.node.ft.stream.model is not None
        push = np.array([4.0, -2.0, 7.0, 0.3, 0.1, -0.2])
        q = POSES[2]
        send(harness, 20.0, q, zero, tool_wrench(true_arm, q, zero, zero, mount)[0] + push)
        assert harness.contacts[-1].header.frame_id == "tool0"
        np.testing.assert_allclose(read(harness.contacts[-1]), push, atol=1e-6)
        assert harness.node.tally.total("errors") == 0
