"""In-process ROS 2 test harness: a node under test and a probe node, one executor, real DDS.

Every wait has a timeout; contexts are shut down and nodes destroyed on exit.
"""

from __future__ import annotations

import gc
import time
import traceback
from collections.abc import Callable
from contextlib import contextmanager

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient

TIMEOUT = 30.0  # s, for anything that should happen at once on an idle machine (generous: 2 busy cores)
# s: the executor's wait between checks for what wakes it by itself (a service's reply, a
# task a node hands to its executor): spinning idle every 10 ms costs CPU (rclpy rebuilds
# its wait set each time) that the node's worker threads would use
WOKEN = 0.5


class Harness:
    """Spins the node under test with a probe node that publishes, subscribes and calls."""

    def __init__(self, context: Context, node: Node):
        self.context, self.node = context, node
        self.probe = Node("probe", context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(node)
        self.executor.add_node(self.probe)
        self.received: dict[str, list] = {}

    def spin_until(self, done: Callable[[], bool], timeout: float = TIMEOUT, poll: float = 0.01) -> bool:
        """Spin until ``done()``, checked after each callback or every ``poll`` s: a longer
        poll where what ``done`` waits for wakes the executor itself (a reply, a task)."""
        deadline = time.monotonic() + timeout
        while not done():
            if time.monotonic() > deadline:
                return False
            self.executor.spin_once(timeout_sec=poll)
        return True

    def spin_for(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.01)

    def listen(self, msg_type, topic: str, qos=10) -> list:
        """Messages arriving on ``topic`` from now on, in a list that fills while spinning."""
        inbox = self.received.setdefault(topic, [])
        self.probe.create_subscription(msg_type, topic, inbox.append, qos)
        return inbox

    def publisher(self, msg_type, topic: str, qos=10):
        pub = self.probe.create_publisher(msg_type, topic, qos)
        assert self.spin_until(lambda: pub.get_subscription_count() > 0), f"nobody subscribes to {topic}"
        return pub

    def wait_for_subscribers(self, topic: str) -> None:
        assert self.spin_until(lambda: self.probe.count_subscribers(topic) > 0), f"no subscriber on {topic}"

    def call(self, future_maker: Callable[[], rclpy.task.Future]):
        future = future_maker()
        assert self.spin_until(future.done, poll=WOKEN), "no reply in time"
        return future.result()

    def parameter_client(self) -> AsyncParameterClient:
        client = AsyncParameterClient(self.probe, self.node.get_fully_qualified_name())
        assert client.wait_for_services(timeout_sec=TIMEOUT), "parameter services not up"
        return client

    def set_parameters(self, params: list[Parameter]):
        """Set parameters one by one through the standard service; the results in order,
        once the node has applied what it accepted."""
        client = self.parameter_client()
        results = self.call(lambda: client.set_parameters(params)).results
        self.settle()
        return results

    def set_parameters_atomically(self, params: list[Parameter]):
        client = self.parameter_client()
        result = self.call(lambda: client.set_parameters_atomically(params)).result
        self.settle()
        return result

    def settle(self) -> None:
        """Spin until the node's accepted parameter changes are in force (built off its executor)."""
        rebuild = getattr(self.node, "rebuild", None)
        if rebuild is not None:
            assert self.spin_until(lambda: rebuild.pending_since is None, poll=WOKEN), "parameters not applied in time"

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=1.0)
        self.probe.destroy_node()
        self.node.destroy_node()


@contextmanager
def running(make_node: Callable[..., Node], **node_kwargs):
    """A fresh context with the node built by ``make_node(context=..., **node_kwargs)``."""
    context = Context()
    rclpy.init(context=context)
    harness = None
    try:
        harness = Harness(context, built(make_node, context=context, **node_kwargs))
        yield harness
    finally:
        if harness is not None:
            harness.close()
        rclpy.try_shutdown(context=context)


def built(make_node: Callable[..., Node], **node_kwargs) -> Node:
    """``make_node(**node_kwargs)``; when it raises, the half-made node (its DDS participant)
    is destroyed here, not by a garbage collection in some later test: FastDDS can deadlock
    when a participant is torn down while another of the process is busy with discovery."""
    try:
        return make_node(**node_kwargs)
    except Exception as error:
        cause = error
        while cause is not None:  # the failed __init__'s frames hold the node
            traceback.clear_frames(cause.__traceback__)
            cause = cause.__cause__ or cause.__context__
        gc.collect()
        raise
