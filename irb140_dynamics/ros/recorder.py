"""The record tool's node: `ros2 bag record` of one topic where rosbag2 is not installed
(ROS 2 from PyPI wheels). See tools/record.py; the bag and when it is complete are
identification.bag_recording's.

The recorder waits until the topic has a publisher (its type comes from the graph; after
NAME_TOPICS_AFTER s one line names the topics that have one: a typo shows), then subscribes
reliable when every publisher is, else best effort (as rosbag2 adapts), and hands each
message (CDR) to the bag with its receive time on the node's clock (simulated with
use_sim_time). A motion on the ``reference`` topic (a JointTrajectory) is timed from its
header stamp, else from its arrival; a single point, a hold, is no motion. ``record`` spins
it until the bag is complete, a failure or a stop, and closes the bag.
"""

from __future__ import annotations

import importlib
import time
from pathlib import Path

import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.executors import SingleThreadedExecutor
from rclpy.expand_topic_name import expand_topic_name
from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rclpy.validate_full_topic_name import validate_full_topic_name
from trajectory_msgs.msg import JointTrajectory

from irb140_dynamics.core.io.params_file import rcl_refusal
from irb140_dynamics.core.io.stamps import nanoseconds
from irb140_dynamics.identification.bag_recording import BagRecording

POLL_PERIOD = 0.1  # s between looks at the graph while waiting for the topic
DRAIN_TIME = 1.0  # s: after a stop is asked for, messages already received are written, for at most this long
DRAIN_QUIET = 0.05  # s: until none has come for this long
NAME_TOPICS_AFTER = 3.0  # s without a publisher of the topic: name the topics that have one (once)
TOPICS_NAMED = 12  # at most this many in that line
EVERY_NODES = ("/rosout", "/parameter_events")  # every node publishes these: no answer to a typo


class CannotRecord(Exception):
    """The recording cannot start (one line)."""


def topic_error(name: str) -> str | None:
    """Why ``name`` cannot be a topic name, in one line (rcl's reason); None when it can."""
    try:
        validate_full_topic_name(expand_topic_name(name, "record", "/"))
    except Exception as error:  # noqa: BLE001  (rclpy's InvalidTopicNameException and others)
        return str(error).splitlines()[0].split(", at /")[0]
    return None


def record(argv: list[str], options, out: Path, stop, progress) -> tuple[str, str | None, str | None]:
    """Start rclpy with ``argv``'s ROS arguments (its signal handlers left alone) and record
    ``options.topic`` (``options``: the record tool's, ``out`` the new bag) until it is
    finished, fails or ``stop`` is true, calling ``progress(line)`` as it goes and
    ``progress.end()`` after. The bag is closed whole whatever happens. Why it ended, what
    the bag holds (None if it could not be closed) and the failure (None); CannotRecord when
    it cannot start."""
    try:
        rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    except rclpy_implementation.RCLError as error:
        raise CannotRecord(rcl_refusal(str(error))) from None
    try:
        try:
            recorder = Recorder(options, out)
        except (ValueError, OSError) as error:
            raise CannotRecord(f"{options.out}: {getattr(error, 'strerror', None) or error}") from None
        summary = None
        try:
            why = _spin_until_done(recorder, stop, progress)
        finally:  # whatever happened: the bag closed whole (signals only set flags meanwhile)
            try:
                summary = recorder.bag.close()
            except (OSError, ValueError) as error:  # a full disk
                recorder.bag.failure = recorder.bag.failure or f"{options.out}: cannot close the bag ({error})"
            recorder.destroy_node()
    finally:
        rclpy.try_shutdown()
    return why, summary, recorder.bag.failure


def _spin_until_done(recorder: Recorder, stop, progress) -> str:
    """Spin until the recording is complete, fails or is stopped: why it ended."""
    try:
        from rclpy.experimental import EventsExecutor

        executor = EventsExecutor(context=recorder.context)
    except (ImportError, OSError, ValueError):  # (it enables faulthandler: a stderr without a file fails)
        executor = SingleThreadedExecutor(context=recorder.context)
    executor.add_node(recorder)
    bag = recorder.bag
    try:
        while not stop and not bag.failure and not recorder.check() and recorder.context.ok():
            executor.spin_once(timeout_sec=0.1)
            progress(bag.progress())
        if stop and not bag.finished:  # what is queued was received before the stop
            deadline, count, quiet = time.monotonic() + DRAIN_TIME, -1, time.monotonic()
            while time.monotonic() < min(deadline, quiet + DRAIN_QUIET) and not bag.failure:
                if bag.count != count:
                    count, quiet = bag.count, time.monotonic()
                executor.spin_once(timeout_sec=0.01)
    finally:
        progress.end()
        executor.shutdown()
    return bag.failure or bag.finished or ("interrupted" if stop else "the ROS context shut down")


class Recorder(Node):
    """Records ``options.topic`` into a new bag at ``out`` (``bag``) until it is finished (see
    the module's docstring)."""

    def __init__(self, options, out: Path):
        super().__init__("record")
        self.topic, self.options = self.resolve_topic_name(options.topic), options
        reference = None if options.reference is None else self.resolve_topic_name(options.reference)
        self.bag = BagRecording(out, self.topic, options.duration, options.tail, reference)
        if reference is not None:
            self.create_subscription(JointTrajectory, reference, self._on_reference, 10)
        self._named = False
        # on the steady clock: with use_sim_time, simulated time may stand still until then
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._waiting = self.create_timer(POLL_PERIOD, self._subscribe_when_published, clock=steady)
        self.get_logger().info(f"ready: waiting for a publisher of {self.topic}")

    def _subscribe_when_published(self) -> None:
        publishers = self.get_publishers_info_by_topic(self.topic)
        if self.bag.failure:
            return
        if not publishers:
            if not self._named and time.monotonic() - self.bag.waiting_since >= NAME_TOPICS_AFTER:
                self._named = True
                self.get_logger().warning(f"{self._others()}; still waiting for {self.topic} (Ctrl-C stops)")
            return
        self._waiting.cancel()
        type_name = publishers[0].topic_type
        try:
            package, kind, name = type_name.split("/")  # sensor_msgs/msg/JointState
            message = getattr(importlib.import_module(f"{package}.{kind}"), name)
            self.bag.start(type_name)
        except Exception as error:  # noqa: BLE001  (an unknown type: rosbags and importlib raise many kinds)
            self.bag.failure = f"{self.topic}: cannot record its type {type_name} ({type(error).__name__}: {error})"
            return
        reliable = all(p.qos_profile.reliability == ReliabilityPolicy.RELIABLE for p in publishers)
        policy = ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT
        self.create_subscription(
            message, self.topic, self._on_message, QoSProfile(depth=self.options.depth, reliability=policy), raw=True
        )
        kind = "reliable" if reliable else "best effort"
        self.get_logger().info(f"recording {self.topic} ({type_name}, {kind}) to {self.bag.out}")

    def _others(self) -> str:
        """The topics with a publisher (those of every node left out), in a line."""
        names = sorted(
            f"{name} ({', '.join(types)})"
            for name, types in self.get_topic_names_and_types()
            if name not in EVERY_NODES and self.count_publishers(name) > 0
        )
        if not names:
            return f"no publisher of {self.topic}, nor of any other topic (is the publisher's ROS_DOMAIN_ID this one?)"
        more = f" and {len(names) - TOPICS_NAMED} more" if len(names) > TOPICS_NAMED else ""
        return f"no publisher of {self.topic}; topics with one: {', '.join(names[:TOPICS_NAMED])}{more}"

    def _on_message(self, raw: bytes) -> None:
        self.bag.write(self.get_clock().now().nanoseconds, raw)

    def _on_reference(self, msg: JointTrajectory) -> None:
        if not msg.points:
            return
        last = msg.points[-1].time_from_start
        length = nanoseconds(last.sec, last.nanosec)
        if length <= 0:  # a hold, not a motion
            return
        stamp = nanoseconds(msg.header.stamp.sec, msg.header.stamp.nanosec)
        if self.bag.reference_end is None:
            self.get_logger().info(
                f"following {self.bag.reference}: stops {self.bag.tail:g} s after its motion ends "
                f"({length * 1e-9:g} s long)"
            )
        self.bag.reference_end = (stamp if stamp > 0 else self.get_clock().now().nanoseconds) + length

    def check(self) -> bool:
        """Is the recording complete now (node clock)?"""
        return self.bag.check(self.get_clock().now().nanoseconds)
