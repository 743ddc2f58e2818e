"""A model change never stalls the torque stream: a robot_description is read off the
executor while the model before answers every joint state, then swapped in at once.

id_node runs on its own executor thread, as under ``ros2 run``; joint states come at up to
1 kHz (never in bursts: a late publisher goes on from where it is) with a unique stamp each.
Meanwhile a 50,000-link URDF is published (refused: far over the joint limit, after a
parse of about a second: twice the queue), then a Panda replacing the UR5 in use, then parameter changes
(payload, gravity). Every stamp sent gets
its gravity_torques, whatever the latency: a stall of the executor longer than the queue
(qos.depth) would lose some.
"""

import contextlib
import threading
import time
import uuid

import rclpy
from rcl_interfaces.msg import Log
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import String

from irb140_dynamics.core.urdf import MAX_JOINTS
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.ros.parameters.arm import DESCRIPTION_QOS
from irb140_dynamics.ros.runtime.spin import spin

from ..support.urdf_support import arm_text

RATE = 1000.0  # Hz at most
DEPTH = 500  # joint_states queue of the node: half a second at 1 kHz
LINKS = 50_000  # 10 MB of URDF: its parse takes about a second, twice the queue (DEPTH)
SLOW = 600.0  # s: waits for the refusal (the parse of 10 MB of URDF on a busy machine)
TIMEOUT = 60.0  # s
UR5_JOINTS = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
]
PANDA_JOINTS = [f"panda_joint{i}" for i in range(1, 8)]
RELIABLE = QoSProfile(depth=DEPTH, reliability=ReliabilityPolicy.RELIABLE)


def chain_text(links: int) -> str:
    """A URDF of a chain of ``links`` links, each joint revolute, the last link tool0."""
    parts = ['<robot name="long_chain">']
    parts += [f'<link name="link_{i}"/>' for i in range(links - 1)]
    parts.append('<link name="tool0"/>')
    names = [f"link_{i}" for i in range(links - 1)] + ["tool0"]
    parts += [
        f'<joint name="joint_{i}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i, (parent, child) in enumerate(zip(names, names[1:]))
    ]
    return "".join(parts) + "</robot>"


class Probe:
    """Publishes joint states, the URDFs, and gathers the replies' stamps and the node's log."""

    def __init__(self, context: Context, logger_name: str, namespace: str):
        self.node = Node("stream_probe", context=context, namespace=namespace)
        self.states = self.node.create_publisher(JointState, "joint_states", RELIABLE)
        self.description = self.node.create_publisher(String, "robot_description", DESCRIPTION_QOS)
        self.answered: dict[int, tuple[str, ...]] = {}  # stamp [ns] -> the joints of the reply
        self.log: list[str] = []
        self.node.create_subscription(JointState, "gravity_torques", self._on_torques, QoSProfile(depth=100_000))
        self.node.create_subscription(Log, "/rosout", self._on_log, QoSProfile(depth=1000))
        self._logger_name = logger_name
        self.sent: list[int] = []
        self.streaming = threading.Event()

    def _on_torques(self, msg) -> None:
        self.answered[msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec] = tuple(msg.name)

    def _on_log(self, msg: Log) -> None:
        if msg.name == self._logger_name:  # other tests may run in the same domain
            self.log.append(msg.msg)

    def stream(self) -> None:
        """Joint states of both arms' joints at up to RATE, until ``streaming`` is cleared."""
        msg = JointState(name=UR5_JOINTS + PANDA_JOINTS, position=[0.1] * 13, velocity=[0.0] * 13)
        next_time = time.monotonic()
        while self.streaming.is_set():
            stamp = 1_000_000_000 + len(self.sent) * 1_000_000
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
            self.states.publish(msg)
            self.sent.append(stamp)
            next_time = max(next_time + 1.0 / RATE, time.monotonic())  # late: go on from now, no burst
            time.sleep(max(0.0, next_time - time.monotonic()))


def spin_node(node) -> None:
    """As ``ros2 run`` does (the package's spin: its executor), until the context shuts down."""
    with contextlib.suppress(ExternalShutdownException):
        spin(node)


def spin_probe(executor, context) -> None:
    try:
        while context.ok():
            executor.spin_once(timeout_sec=0.1)
    except ExternalShutdownException:
        pass


def wait_for(done, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while not done():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def test_no_joint_state_goes_unanswered_while_a_urdf_is_refused_or_swapped_in():
    panda = arm_text("panda").replace('"panda_hand_tcp"', '"tool0"')  # the tip link is read-only
    huge = chain_text(LINKS)
    context = Context()
    rclpy.init(context=context)
    overrides = [
        Parameter("model.source", value="robot_description"),
        Parameter("model.tip_link", value="tool0"),
        Parameter("qos.depth", value=DEPTH),
        Parameter("qos.reliability", value="reliable"),
    ]
    namespace = f"/stream_{uuid.uuid4().hex[:8]}"  # topics of this test's own
    node = IdNode(context=context, parameter_overrides=overrides, cli_args=["--ros-args", "-r", f"__ns:={namespace}"])
    probe = Probe(context, node.get_logger().name, namespace)
    probe_executor = SingleThreadedExecutor(context=context)
    probe_executor.add_node(probe.node)
    threads = [
        threading.Thread(target=spin_node, args=(node,), daemon=True),
        threading.Thread(target=spin_probe, args=(probe_executor, context), daemon=True),
    ]
    streamer = threading.Thread(target=probe.stream, daemon=True)
    try:
        for thread in threads:
            thread.start()
        probe.description.publish(String(data=arm_text("ur5")))
        assert wait_for(lambda: node.settings is not None, TIMEOUT), "the UR5 never came into use"
        assert wait_for(lambda: probe.states.get_subscription_count() > 0, TIMEOUT)
        probe.streaming.set()
        streamer.start()
        assert wait_for(lambda: len(probe.answered) >= 100, TIMEOUT), "no torques for the stream"

        probe.description.publish(String(data=huge))
        sent_before = len(probe.sent)
        assert wait_for(lambda: any("refused a robot_description" in line for line in probe.log), SLOW)
        during_refusal = probe.sent[sent_before : len(probe.sent)]
        probe.description.publish(String(data=panda))
        assert wait_for(lambda: node.settings.model.joint_names == tuple(PANDA_JOINTS), TIMEOUT)
        swapped_at = len(probe.sent)
        assert wait_for(lambda: len(probe.sent) >= swapped_at + 100, TIMEOUT)
        client = AsyncParameterClient(probe.node, node.get_fully_qualified_name())
        for change in (Parameter("payload.mass", value=3.0), Parameter("gravity", value=[0.0, 1.0, -9.8])):
            future = client.set_parameters([change])
            assert wait_for(future.done, TIMEOUT) and future.result().results[0].successful
        assert wait_for(lambda: node.settings.model.payload.mass == 3.0, TIMEOUT)
        changed_at = len(probe.sent)
        assert wait_for(lambda: len(probe.sent) >= changed_at + 100, TIMEOUT)
        probe.streaming.clear()
        streamer.join(TIMEOUT)

        wait_for(lambda: len(probe.answered) >= len(probe.sent), TIMEOUT)  # then see what is missing
        missing = [stamp for stamp in probe.sent if stamp not in probe.answered]
        assert missing == [], f"{len(missing)} of {len(probe.sent)} joint states unanswered"
        assert {probe.answered[stamp] for stamp in during_refusal} == {tuple(UR5_JOINTS)}  # the model before
        assert probe.answered[probe.sent[-1]] == tuple(PANDA_JOINTS)
        refusal = next(line for line in probe.log if "refused a robot_description" in line)
        assert "keeping the model of 6 joints" in refusal and f"more than the limit of {MAX_JOINTS}" in refusal, refusal
    finally:
        probe.streaming.clear()
        rclpy.try_shutdown(context=context)
        for thread in threads:
            thread.join(TIMEOUT)
        probe_executor.shutdown()
        probe.node.destroy_node()
        node.destroy_node()
