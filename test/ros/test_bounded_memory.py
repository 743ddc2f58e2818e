"""Nothing of ours grows with the inputs: counters, caches, warning keys,
timers and threads stay bounded, and the Python memory allocated by our code stops growing
after a warm-up, under ever-new joint names, bad messages, references, parameter changes
(models compiled anew) and checks. Growth below the Python allocator (rclpy, DDS) is for
the soak of bench/bench_nodes.py, side by side with a bare relay."""

import gc
import os
import threading
import tracemalloc
from pathlib import Path

import pytest
from rclpy.parameter import Parameter

import irb140_dynamics
from irb140_dynamics.core.payload import family as payload_family
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode

from ..support.fuzz_inputs import Fuzzer
from ..support.ros_harness import running

# the package's own files (not a path that merely contains its name: a clone may be named so)
OURS = str(Path(irb140_dynamics.__file__).parent) + os.sep  # as the import machinery names them
# bytes allocated by our code during the measured inputs and still held: the objects that
# replaced others (settings, the latest state) and CPython's free lists count in full; a
# leak of 100 bytes per input would be 60 kB or more
GROWTH_LIMIT = 50_000


def our_growth(before: tracemalloc.Snapshot, after: tracemalloc.Snapshot) -> tuple[int, list]:
    stats = [s for s in after.compare_to(before, "lineno") if s.traceback[0].filename.startswith(OURS)]
    top = sorted(stats, key=lambda s: -s.size_diff)[:5]
    return sum(s.size_diff for s in stats), [f"{s.traceback[0]}: {s.size_diff:+} B in {s.count_diff:+}" for s in top]


def measure(feed, warmup: int, count: int, settle=lambda: None) -> tuple[int, list]:
    """What our code allocated while fed ``count`` inputs (after ``warmup`` untraced) and
    still holds: replaced objects count in full, so a bounded state shows as a few kB.
    ``settle()`` before each snapshot: empties what is bounded by a cap of its own."""
    feed(warmup)
    settle()
    gc.collect()  # compiled kernels are cycles (functions and their namespace)
    tracemalloc.start()
    try:
        before = tracemalloc.take_snapshot()
        feed(count)
        settle()
        gc.collect()
        return our_growth(before, tracemalloc.take_snapshot())
    finally:
        tracemalloc.stop()


@pytest.mark.slow
def test_id_node_holds_no_more_memory_after_warming_up(monkeypatch):
    fuzz = Fuzzer(seed=11)
    with running(IdNode, parameter_overrides=[Parameter("acceleration.mode", value="differentiate")]) as harness:
        node = harness.node
        threads = threading.active_count()
        step = [0]

        def feed(count):
            for _ in range(count):
                step[0] += 1
                node._on_joint_state(fuzz.joint_state().msg)
                if step[0] % 10 == 0:
                    node._on_reference(fuzz.reference().msg)
                if step[0] % 100 == 0:  # another arm (3 of them: compiled once, then shared), a payload
                    node.set_parameters([Parameter("joint_2.link.mass", value=20.0 + step[0] // 100 % 3)])
                    node.set_parameters([Parameter("payload.mass", value=step[0] % 1000 / 100)])
                    harness.settle()
                if step[0] % 500 == 0:
                    node._publish_diagnostics()

        growth, top = measure(feed, warmup=400, count=800)
        assert growth < GROWTH_LIMIT, top
        assert len(node._order._cache) <= 16
        assert len(node.counts) <= 30 and all(key.count(".") == 1 for key in node.counts), dict(node.counts)
        assert len(node.tally._next_warning) <= 3
        timers = list(node.timers)  # diagnostics and markers: builds are handed back as executor tasks, no timer
        assert len(timers) == 2
        assert threading.active_count() == threads
        assert not any(key.endswith(".errors") for key in node.counts)


@pytest.mark.slow
def test_payload_check_node_holds_no_more_memory_after_warming_up():
    fuzz = Fuzzer(seed=12)
    with running(PayloadCheckNode, parameter_overrides=[Parameter("diagnostics.period", value=0.0)]) as harness:
        node = harness.node
        step = [0]

        def feed(count):
            for _ in range(count):
                step[0] += 1
                node._on_joint_state(fuzz.joint_state().msg)
                if step[0] % 20 == 0:
                    node.check()
                if step[0] % 100 == 0:  # a payload change: analysed off the executor
                    node.set_parameters([Parameter("payload.mass", value=step[0] % 1000 / 100)])
                    harness.settle()

        def settle():  # the payload estimator keeps at most max_samples rest samples, a payload
            detector = node.estimator.detector  # family its last 8 proofs, the last FAMILIES families
            assert len(detector.samples) <= detector.max_samples
            detector.clear()
            with payload_family._LOCK:
                assert len(payload_family._FAMILIES) <= payload_family.FAMILIES
                for family in payload_family._FAMILIES.values():
                    assert len(family._proven) <= 8
                    family._proven.clear()

        growth, top = measure(feed, warmup=1000, count=600, settle=settle)  # a warm-up through every payload mass
        # The certified analysis keeps more that is bounded (the proofs' report strings and
        # shapes of its remembered families): 39 kB after 600 inputs, 45 kB after 1800.
        assert growth < 2 * GROWTH_LIMIT, top
        assert len(node._order._cache) <= 16 and len(node.counts) <= 20
        assert not list(node.timers)  # no timer polls: ~/check's waits are one-shot timers, gone with their request
        assert not any(key.endswith(".errors") for key in node.counts)
