"""The nodes as their own processes, driven by main() as `ros2 run` starts them: topics,
parameter services and ~/check all answer under the executor main() uses."""

import math
import time

import numpy as np
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from irb140_dynamics.core import RigidBody, gravity, irb140

from ..support.node_process import TIMEOUT, wait_for_line

READY = 120.0  # s: a node's start and first analysis on two busy cores (see test_launch_files)
STRETCHED = [0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0]


def test_id_node_process_computes_and_takes_a_parameter_change(probe, process):
    process("irb140_dynamics.nodes.id_node.node")
    received = []
    probe.create_subscription(JointState, "gravity_torques", received.append, 10)
    joint_states = probe.create_publisher(JointState, "joint_states", 10)
    state = JointState(name=[f"joint_{i}" for i in range(1, 7)], position=STRETCHED)
    probe.spin_until(lambda: received, each=lambda: joint_states.publish(state))
    np.testing.assert_allclose(received[-1].effort, gravity(irb140(), STRETCHED), rtol=1e-12, atol=1e-12)

    client = AsyncParameterClient(probe, "id_node")
    assert client.wait_for_services(timeout_sec=TIMEOUT)
    future = client.set_parameters([Parameter("payload.mass", value=6.0)])
    probe.spin_until(future.done)
    assert future.result().results[0].successful
    loaded = gravity(irb140(payload=RigidBody(6.0)), STRETCHED)
    received.clear()
    probe.spin_until(
        lambda: received and np.allclose(received[-1].effort, loaded, rtol=1e-12),
        each=lambda: joint_states.publish(state),
    )


def test_payload_check_node_process_answers_check(probe, process):
    """~/check of the node process, asked once its first analysis is in force (the ready line
    without "still running"), with an analysis budget as long as that wait: the verdict then
    depends on no machine's speed. A check held while an analysis runs is tested in
    test_payload_check_wait_process.py."""
    node = process(
        "irb140_dynamics.nodes.payload_check_node.node",
        *("-p", "payload.mass:=7.0", "-p", f"check.analysis_timeout:={READY:g}"),
    )
    assert wait_until_analysed(node), "the first analysis was not in force in time"
    client = probe.create_client(Trigger, "/payload_check_node/check")
    assert client.wait_for_service(timeout_sec=TIMEOUT)
    future = client.call_async(Trigger.Request())
    probe.spin_until(future.done)
    reply = future.result()
    assert not reply.success and reply.message.startswith("OVER-LIMIT: 7.000 kg does not fit: "), reply.message
    assert "joint_2" in reply.message.splitlines()[0]


def wait_until_analysed(node) -> bool:
    """Read payload_check_node's output until its ready line for the analysed parameters
    (the one logged at once when the analysis was done within the startup wait, else the
    one logged when it is in force), within READY."""
    lines, deadline = [], time.monotonic() + READY
    while wait_for_line(node, "ready: ~/check", lines, max(0.0, deadline - time.monotonic())):
        if "still running" not in lines[-1]:
            return True
    return False
