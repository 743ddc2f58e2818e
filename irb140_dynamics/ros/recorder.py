"""A topic recorded to a ROS 2 bag (.mcap) with rosbags' writer: `ros2 bag record` for an
install without rosbag2 (ROS 2 from PyPI wheels). See tools/record.py.

The messages are written as they arrive, serialized (CDR), with the receive time on the
node's clock (simulated time with use_sim_time, as `ros2 bag record --use-sim-time`). The
message type comes from the graph: the recorder waits until the topic has a publisher.
Its subscription offers what every publisher gives: reliable when all of them are
reliable, else best effort (as rosbag2 adapts). While none comes, after NAME_TOPICS_AFTER
seconds one line on stderr names the topics that have a publisher (a typo shows), and the
recorder keeps waiting: the publisher may start later. No message at all: no bag is left.

It finishes by itself (``finished`` says why) ``duration`` s after the first message, or
``tail`` s after the end of the motion last sent on a ``reference`` topic (a
JointTrajectory, as id_node follows it: from its header stamp, or from its arrival when
unstamped; a single point, a hold, is no motion). Nothing here stops the process:
``record`` spins it until it is finished, fails or is asked to stop, and closes the bag.
"""

from __future__ import annotations

import importlib
import shutil
import time
from pathlib import Path

import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.expand_topic_name import expand_topic_name
from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rclpy.validate_full_topic_name import validate_full_topic_name

from irb140_dynamics.core.errors import counted
from irb140_dynamics.identification.recording import bag_connection, open_bag
from irb140_dynamics.ros.runtime.spin import init_error

DEFAULT_DEPTH = 1000  # the subscription's queue: a burst the writer may lag behind
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
    """rclpy started with ``argv``'s ROS arguments (its signal handlers left alone), then
    ``options.topic`` recorded into the new bag ``out`` (``options.out`` as typed, named in
    errors; a Recorder of ``options``' duration, depth, reference and tail) until it is
    finished, fails or ``stop`` is true; ``progress(line)`` is called as it goes, and
    ``progress.end()`` when it stops. The bag is closed whole whatever happens. Returns why
    it ended, what the bag holds (None if it could not be closed) and the failure (None);
    CannotRecord when it cannot start."""
    try:
        rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    except rclpy_implementation.RCLError as error:
        raise CannotRecord(init_error(error)) from None
    try:
        try:
            recorder = Recorder(options.topic, out, options.duration, options.depth, options.reference, options.tail)
        except (ValueError, OSError) as error:
            raise CannotRecord(f"{options.out}: {getattr(error, 'strerror', None) or error}") from None
        summary = None
        try:
            why = _spin_until_done(recorder, stop, progress)
        finally:  # whatever happened: the bag closed whole (signals only set flags meanwhile)
            try:
                summary = recorder.close()
            except (OSError, ValueError) as error:  # a full disk
                recorder.failure = recorder.failure or f"{options.out}: cannot close the bag ({error})"
            recorder.destroy_node()
    finally:
        rclpy.try_shutdown()
    return why, summary, recorder.failure


def _spin_until_done(recorder: Recorder, stop, progress) -> str:
    """Spin until the recording is complete, fails or is stopped: why it ended."""
    executor = _executor(recorder)
    try:
        while not stop and not recorder.failure and not recorder.check() and recorder.context.ok():
            executor.spin_once(timeout_sec=0.1)
            progress(recorder.progress())
        if stop and not recorder.finished:  # what is queued was received before the stop
            deadline, count, quiet = time.monotonic() + DRAIN_TIME, -1, time.monotonic()
            while time.monotonic() < min(deadline, quiet + DRAIN_QUIET) and not recorder.failure:
                if recorder.count != count:
                    count, quiet = recorder.count, time.monotonic()
                executor.spin_once(timeout_sec=0.01)
    finally:
        progress.end()
        executor.shutdown()
    return recorder.failure or recorder.finished or ("interrupted" if stop else "the ROS context shut down")


def _executor(node: Node):
    try:
        from rclpy.experimental import EventsExecutor

        executor = EventsExecutor(context=node.context)
    except (ImportError, OSError, ValueError):  # (it enables faulthandler: a stderr without a file fails)
        from rclpy.executors import SingleThreadedExecutor

        executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    return executor


def message_class(type_name: str):
    """sensor_msgs/msg/JointState -> the class sensor_msgs.msg.JointState."""
    package, kind, name = type_name.split("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


class Recorder(Node):
    """Records ``topic`` into a new bag at ``out`` until ``finished`` (see the module's docstring)."""

    def __init__(
        self,
        topic: str,
        out: Path,
        duration: float = 0.0,
        depth: int = DEFAULT_DEPTH,
        reference: str | None = None,
        tail: float = 1.0,
        **kwargs,
    ):
        super().__init__("record", **kwargs)
        if not duration >= 0.0 or not tail >= 0.0:
            raise ValueError(f"--duration and --tail: must be >= 0, got {duration}, {tail}")
        self.topic, self.out, self.duration, self.depth = self.resolve_topic_name(topic), Path(out), duration, depth
        self.tail = tail
        self.finished: str | None = None  # why the recording is complete
        self.failure: str | None = None  # why it cannot go on (one line)
        self.reference_end: int | None = None  # ns, node clock: where the last motion ends
        if reference is not None:
            from trajectory_msgs.msg import JointTrajectory

            self.reference = self.resolve_topic_name(reference)
            self.create_subscription(JointTrajectory, self.reference, self._on_reference, 10)
        self._writer = open_bag(self.out)
        self._connection = None
        self._waiting_since, self._named = time.monotonic(), False
        self.count, self.first, self.last = 0, None, None  # messages, receive times [ns]
        # on the steady clock: with use_sim_time, simulated time may stand still until then
        self._waiting = self.create_timer(
            POLL_PERIOD, self._subscribe_when_published, clock=Clock(clock_type=ClockType.STEADY_TIME)
        )
        self.get_logger().info(f"ready: waiting for a publisher of {self.topic}")

    def _subscribe_when_published(self) -> None:
        publishers = self.get_publishers_info_by_topic(self.topic)
        if self.failure:
            return
        if not publishers:
            if not self._named and time.monotonic() - self._waiting_since >= NAME_TOPICS_AFTER:
                self._named = True
                self.get_logger().warning(f"{self._others()}; still waiting for {self.topic} (Ctrl-C stops)")
            return
        self._waiting.cancel()
        type_name = publishers[0].topic_type
        try:
            message = message_class(type_name)
            self._connection = bag_connection(self._writer, self.topic, type_name)
        except Exception as error:  # noqa: BLE001  (an unknown type: rosbags and importlib raise many kinds)
            self.failure = f"{self.topic}: cannot record its type {type_name} ({type(error).__name__}: {error})"
            return
        reliable = all(p.qos_profile.reliability == ReliabilityPolicy.RELIABLE for p in publishers)
        qos = QoSProfile(
            depth=self.depth, reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT
        )
        self.create_subscription(message, self.topic, self._on_message, qos, raw=True)
        self.get_logger().info(
            f"recording {self.topic} ({type_name}, {'reliable' if reliable else 'best effort'}) to {self.out}"
        )

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
        if self.finished or self.failure:
            return
        now = self.get_clock().now().nanoseconds
        if self.first is None:
            self.first = now
        elif self.check(now):
            return
        try:
            self._writer.write(self._connection, now, raw)
        except (OSError, ValueError) as error:  # a full disk
            self.failure = f"{self.out}: cannot write ({getattr(error, 'strerror', None) or error})"
            return
        self.count, self.last = self.count + 1, now

    def _on_reference(self, msg) -> None:
        if not msg.points:
            return
        last = msg.points[-1].time_from_start
        length = last.sec * 1_000_000_000 + last.nanosec
        if length <= 0:  # a hold, not a motion
            return
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        start = stamp if stamp > 0 else self.get_clock().now().nanoseconds
        if self.reference_end is None:
            self.get_logger().info(
                f"following {self.reference}: stops {self.tail:g} s after its motion ends ({length * 1e-9:g} s long)"
            )
        self.reference_end = start + length

    def check(self, now: int | None = None) -> bool:
        """Is the recording complete at ``now`` (node clock, ns)? Sets ``finished``."""
        if self.finished:
            return True
        now = self.get_clock().now().nanoseconds if now is None else now
        if self.duration and self.first is not None and now - self.first >= self.duration * 1e9:
            self.finished = f"{self.duration:g} s after the first message"
        elif self.reference_end is not None and now >= self.reference_end + self.tail * 1e9:
            self.finished = f"{self.tail:g} s after the end of the motion on {self.reference}"
        return self.finished is not None

    def progress(self) -> str:
        """What is recorded so far, in a line."""
        if self._connection is None:
            return f"waiting for a publisher of {self.topic}: {time.monotonic() - self._waiting_since:.0f} s"
        span = 0.0 if self.first is None else (self.last - self.first) * 1e-9
        goal = f" of {self.duration:g} s" if self.duration else ""
        return f"recording {self.topic}: {counted(self.count, 'message')}, {span:.1f} s{goal}"

    def close(self) -> str:
        """Close the bag (call once, with signals held off: a bag half closed is unreadable);
        what it holds, in a line. A bag without a message is removed (the recorder made it:
        the folder was new)."""
        self._writer.close()
        if self.count == 0:
            shutil.rmtree(self.out, ignore_errors=True)
            return f"no message came on {self.topic}: nothing written"
        span = 0.0 if self.first is None else (self.last - self.first) * 1e-9
        return f"wrote {self.out}: {counted(self.count, 'message')} of {self.topic} over {span:.3f} s"
