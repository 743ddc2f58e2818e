"""A topic recorded to a ROS 2 bag (.mcap) with rosbags' writer: `ros2 bag record` for an
install without rosbag2 (ROS 2 from PyPI wheels). See tools/record.py.

The messages are written as they arrive, serialized (CDR), with the receive time on the
node's clock (simulated time with use_sim_time, as `ros2 bag record --use-sim-time`). The
message type comes from the graph: the recorder waits until the topic has a publisher.
Its subscription offers what every publisher gives: reliable when all of them are
reliable, else best effort (as rosbag2 adapts).
"""

from __future__ import annotations

import importlib
from pathlib import Path

from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

DEFAULT_DEPTH = 1000  # the subscription's queue: a burst the writer may lag behind
POLL_PERIOD = 0.1  # s between looks at the graph while waiting for the topic


def message_class(type_name: str):
    """sensor_msgs/msg/JointState -> the class sensor_msgs.msg.JointState."""
    package, kind, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


def open_bag(path: Path):
    """rosbags' writer of a new bag directory at ``path`` (ValueError when it exists)."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    if path.exists():
        raise ValueError(f"{path}: exists already; give a new name")
    writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    return writer


class Recorder(Node):
    """Records ``topic`` into a new bag at ``out``, for ``duration`` s of the node's clock
    after the first message (0: until Ctrl-C)."""

    def __init__(self, topic: str, out: Path, duration: float = 0.0, depth: int = DEFAULT_DEPTH, **kwargs):
        super().__init__("record", **kwargs)
        if not duration >= 0.0:
            raise ValueError(f"--duration: must be >= 0, got {duration}")
        self.topic, self.out, self.duration, self.depth = self.resolve_topic_name(topic), Path(out), duration, depth
        self._writer = open_bag(self.out)
        self._connection = None
        self.count, self.first, self.last = 0, None, None  # messages, receive times [ns]
        # on the steady clock: with use_sim_time, simulated time may stand still until then
        self._waiting = self.create_timer(
            POLL_PERIOD, self._subscribe_when_published, clock=Clock(clock_type=ClockType.STEADY_TIME)
        )
        self.get_logger().info(f"ready: waiting for a publisher of {self.topic}")

    def _subscribe_when_published(self) -> None:
        publishers = self.get_publishers_info_by_topic(self.topic)
        if not publishers:
            return
        self._waiting.cancel()
        type_name = publishers[0].topic_type
        from rosbags.typesys import Stores, get_typestore

        self._connection = self._writer.add_connection(
            self.topic, type_name, typestore=get_typestore(Stores.ROS2_JAZZY)
        )
        reliable = all(p.qos_profile.reliability == ReliabilityPolicy.RELIABLE for p in publishers)
        qos = QoSProfile(
            depth=self.depth, reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT
        )
        self.create_subscription(message_class(type_name), self.topic, self._on_message, qos, raw=True)
        self.get_logger().info(
            f"recording {self.topic} ({type_name}, {'reliable' if reliable else 'best effort'}) to {self.out}"
        )

    def _on_message(self, raw: bytes) -> None:
        now = self.get_clock().now().nanoseconds
        if self.first is None:
            self.first = now
        elif self.duration and now - self.first >= self.duration * 1e9:
            self.context.try_shutdown()  # main() then closes the bag
            return
        self._writer.write(self._connection, now, raw)
        self.count, self.last = self.count + 1, now

    def close(self) -> str:
        """Close the bag; what it holds, in a line."""
        self._writer.close()
        span = 0.0 if self.first is None else (self.last - self.first) * 1e-9
        return f"wrote {self.out}: {self.count} messages of {self.topic} over {span:.3f} s"
