"""The builder's poll timer is made once and reused (rcl keeps ~80 B of every timer made);
its worker thread ends with the work."""

import threading

from rclpy.node import Node

from irb140_dynamics.ros.runtime.builder import Builder, Failed

from ..support.ros_harness import running


def _builder(node: Node, delivered: list, threads: list) -> Builder:
    def build(job, previous):
        if threading.current_thread() not in threads:  # the Thread objects: an ident may be reused
            threads.append(threading.current_thread())
        if job == "fail":
            raise ValueError("refused")
        return (job, previous)

    return Builder(node, build, lambda generation, result: delivered.append((generation, result)), "test builder")


def test_builds_reuse_one_timer_and_leave_no_thread():
    with running(lambda **kw: Node("builder_test", **kw)) as harness:
        delivered, threads = [], []
        builder = _builder(harness.node, delivered, threads)
        for generation, job in enumerate(["a", "b", "fail", "c"], start=1):
            builder.submit(generation, job)
            assert harness.spin_until(lambda: len(delivered) == generation)
            assert harness.spin_until(lambda: not builder._work.thread)  # the worker ends with the work
        assert [g for g, _ in delivered] == [1, 2, 3, 4]
        assert delivered[1][1] == ("b", ("a", None)) and isinstance(delivered[2][1], Failed)
        assert delivered[3][1] == ("c", ("b", ("a", None)))  # a failed build leaves the previous result
        assert threading.current_thread() not in threads
        assert harness.spin_until(lambda: not any(t.is_alive() for t in threads))
        timers = list(harness.node.timers)
        assert len(timers) == 1 and timers[0].is_canceled()  # made once, cancelled when idle
