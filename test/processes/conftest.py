"""Fixtures of the process tests: a probe node in the test process, and the package's
executables started as processes (killed at the end of the test)."""

import time

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from ..support.node_process import TIMEOUT, module_command, start


def probe_on(kind):
    """A probe node spun by an executor of ``kind`` (see probe)."""
    context = Context()
    rclpy.init(context=context)
    node = Node("process_probe", context=context)
    executor = kind(context=context)
    executor.add_node(node)

    def spin_until(done, timeout=TIMEOUT, each=None):
        deadline = time.monotonic() + timeout
        while not done():
            assert time.monotonic() < deadline, "timed out"
            if each:
                each()
            executor.spin_once(timeout_sec=0.05)

    node.spin_until = spin_until
    try:
        yield node
    finally:
        executor.shutdown(timeout_sec=1.0)
        node.destroy_node()
        rclpy.try_shutdown(context=context)


@pytest.fixture
def probe():
    """A node in the test process and its spin_until(done, timeout, each): spun by rclpy's
    SingleThreadedExecutor (futures and coroutines included)."""
    yield from probe_on(SingleThreadedExecutor)


@pytest.fixture
def stream_probe():
    """probe, spun by rclpy's EventsExecutor where this rclpy has it: under half the CPU per
    message taken (as the nodes spin, ros.runtime.spin), for a test that takes thousands
    (subscriptions, timers, service clients; no coroutine callbacks)."""
    try:
        from rclpy.experimental import EventsExecutor
    except ImportError:
        EventsExecutor = SingleThreadedExecutor  # noqa: N806
    yield from probe_on(EventsExecutor)


@pytest.fixture
def process():
    processes = []

    def launch(module, *ros_args):
        processes.append(start(module_command(module, *ros_args)))
        return processes[-1]

    yield launch
    for p in processes:
        p.kill()
        p.communicate(timeout=10)
