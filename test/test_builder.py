"""The builder's worker thread and poll timer are made once and reused: a thread or timer
made per parameter change grew the node's memory (rcl keeps ~80 B of every timer made)."""

import threading

from rclpy.node import Node

from irb140_dynamics.ros import builder as builder_module
from irb140_dynamics.ros.builder import Builder, Failed

from .ros_harness import running


def _builder(node: Node, delivered: list, threads: list) -> Builder:
    def build(job, previous):
        if threading.current_thread() not in threads:  # the Thread objects: an ident may be reused
            threads.append(threading.current_thread())
        if job == "fail":
            raise ValueError("refused")
        return (job, previous)

    return Builder(node, build, lambda generation, result: delivered.append((generation, result)), "test builder")


def test_successive_builds_reuse_one_thread_and_one_timer():
    with running(lambda **kw: Node("builder_test", **kw)) as harness:
        delivered, threads = [], []
        builder = _builder(harness.node, delivered, threads)
        for generation, job in enumerate(["a", "b", "fail", "c"], start=1):
            builder.submit(generation, job)
            assert harness.spin_until(lambda: len(delivered) == generation)
        assert [g for g, _ in delivered] == [1, 2, 3, 4]
        assert delivered[1][1] == ("b", ("a", None)) and isinstance(delivered[2][1], Failed)
        assert delivered[3][1] == ("c", ("b", ("a", None)))  # a failed build leaves the previous result
        assert len(threads) == 1 and threading.current_thread() not in threads
        timers = list(harness.node.timers)
        assert len(timers) == 1 and timers[0].is_canceled()  # made once, cancelled when idle


def test_the_worker_thread_ends_when_no_job_comes(monkeypatch):
    monkeypatch.setattr(builder_module, "LINGER", 0.05)
    with running(lambda **kw: Node("builder_test", **kw)) as harness:
        delivered, threads = [], []
        builder = _builder(harness.node, delivered, threads)
        builder.submit(1, "a")
        assert harness.spin_until(lambda: len(delivered) == 1)
        assert harness.spin_until(lambda: not builder._work.thread)
        builder.submit(2, "b")  # a new thread takes the next job
        assert harness.spin_until(lambda: len(delivered) == 2)
        assert len(threads) == 2
