"""The builder's poll timer is made once and reused (rcl keeps ~80 B of every timer made);
its worker thread ends with the work; a newer job or the context's shutdown cancels the
build under way."""

import threading

from rclpy.node import Node

from irb140_dynamics.core.payload.stop import current_stop, out_of_time
from irb140_dynamics.ros.runtime.builder import Builder, Failed

from ..support.ros_harness import TIMEOUT, running


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


def test_a_newer_job_cancels_the_build_under_way():
    """A build that checks core.payload.stop (the payload analysis does) stops at
    its next check once a newer job comes, and is not delivered; the newer one is."""
    with running(lambda **kw: Node("builder_test", **kw)) as harness:
        delivered, survived = [], []
        started = threading.Event()

        def build(job, previous):
            if job == "endless":
                started.set()
                stop = current_stop()
                while True:  # an analysis with no end of its own
                    cancelled = stop.cancel.is_set()
                    out_of_time()  # raises once cancelled
                    if cancelled:
                        survived.append(job)  # a check after the cancel that did not stop it
            return (job, previous)

        builder = Builder(harness.node, build, lambda g, result: delivered.append((g, result)), "test builder")
        builder.submit(1, "first")
        assert harness.spin_until(lambda: len(delivered) == 1)
        builder.submit(2, "endless")
        assert started.wait(TIMEOUT)
        builder.submit(3, "newest")
        assert harness.spin_until(lambda: len(delivered) == 2)
        assert delivered == [(1, ("first", None)), (3, ("newest", ("first", None)))]  # the cancelled one left out
        assert builder.cancelled == 1 and survived == []  # stopped at its first check after the cancel
        assert harness.spin_until(lambda: not builder._work.thread)


def test_the_context_shutting_down_cancels_the_build_under_way():
    """A node's context shut down (Ctrl-C, a test's end): its worker stops building."""
    with running(lambda **kw: Node("builder_test", **kw)) as harness:
        started, ended = threading.Event(), threading.Event()

        def build(job, previous):
            started.set()
            try:
                while True:
                    out_of_time()
            finally:
                ended.set()

        builder = Builder(harness.node, build, lambda g, result: None, "test builder")
        builder.submit(1, "endless")
        assert started.wait(TIMEOUT)
        harness.context.try_shutdown()
        assert ended.wait(TIMEOUT) and builder.cancelled == 1


def test_a_build_done_here_cancels_the_workers_and_the_poll_ends():
    """A quick change built on the executor thread supersedes the worker's build under way."""
    with running(lambda **kw: Node("builder_test", **kw)) as harness:
        delivered, started = [], threading.Event()

        def build(job, previous):
            while job == "endless":
                started.set()
                out_of_time()  # raises once cancelled
            return job

        builder = Builder(harness.node, build, lambda g, result: delivered.append((g, result)), "test builder")
        builder.submit(1, "endless")
        assert started.wait(TIMEOUT)
        builder.build_here(2, "quick")
        assert delivered == [(2, "quick")]
        assert harness.spin_until(lambda: builder.cancelled == 1 and not builder._work.thread)
        assert harness.spin_until(lambda: all(timer.is_canceled() for timer in harness.node.timers))
        assert delivered == [(2, "quick")]
