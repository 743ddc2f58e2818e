"""Fixtures of the process tests: a probe node in the test process, and the package's
executables started as processes (killed at the end of the test)."""

import time

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from ..support.node_process import TIMEOUT, module_command, start


@pytest.fixture
def probe():
    context = Context()
    rclpy.init(context=context)
    node = Node("process_probe", context=context)
    executor = SingleThreadedExecutor(context=context)
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
def process():
    processes = []

    def launch(module, *ros_args):
        processes.append(start(module_command(module, *ros_args)))
        return processes[-1]

    yield launch
    for p in processes:
        p.kill()
        p.communicate(timeout=10)
