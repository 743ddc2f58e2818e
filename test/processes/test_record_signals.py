"""record never loses what it received: one, two or three Ctrl-C / SIGTERM in any phase
(starting, waiting for the topic, recording, stopping and closing) stop it with exit status
0 and a bag that rosbags and `identify`'s reader read, holding every message published
well before the first signal, in order and without a gap (no bag when none came). Seeded: the same cases each run."""

import signal
import sys
import time

import numpy as np
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore
from sensor_msgs.msg import JointState

from irb140_dynamics.identification.recording import Recording

from ..support.common import sweep
from ..support.node_process import TIMEOUT, handles_sigterm, start, wait_for_line

NAMES = [f"joint_{i}" for i in range(1, 7)]
PERIOD = 1 / 200.0  # s between messages
SETTLED = 0.5  # s: a message published this long before the first signal has surely arrived


def cases(seed: int = 23, count: int = sweep(4, 32)):
    rng = np.random.default_rng(seed)
    phases = ["starting", "waiting", "recording", "recording"]
    for k in range(count):
        signals = [int(rng.choice([signal.SIGINT, signal.SIGTERM])) for _ in range(int(rng.integers(1, 4)))]
        gaps = rng.uniform(0.0, 0.05, len(signals)).round(3).tolist()  # s between them: closing is hit too
        yield pytest.param(phases[k % len(phases)], signals, gaps, float(rng.uniform(0.0, 0.5)), id=f"case{k}")


def readable(bag) -> np.ndarray:
    """The efforts of joint_1 in the bag, read by rosbags and by identify's reader (a bag
    closed before the topic had a publisher has no topic: rosbags reads it, empty)."""
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        count = sum(1 for _ in reader.messages())
        if not reader.connections:
            return np.zeros(0)
    chunks = list(Recording(bag, NAMES).chunks())
    efforts = np.concatenate([c.effort[:, 0] for c in chunks]) if chunks else np.zeros(0)
    assert len(efforts) == count
    return efforts


@pytest.mark.slow
@pytest.mark.parametrize("phase, signals, gaps, delay", list(cases()))
def test_signals_in_any_phase_leave_a_whole_bag(probe, tmp_path, phase, signals, gaps, delay):
    out = tmp_path / "run"
    process = start([sys.executable, "-m", "irb140_dynamics.tools.record", "--out", str(out)])
    lines, published = [], []  # (time, k)
    publisher = None
    try:
        if phase == "starting":  # from when the tool takes signals (not in the interpreter's own start-up)
            probe.spin_until(lambda: handles_sigterm(process.pid))
            time.sleep(delay)
        else:
            assert wait_for_line(process, "ready", lines, TIMEOUT), "".join(lines)
        if phase == "recording":
            qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
            publisher = probe.create_publisher(JointState, "joint_states", qos)
            assert wait_for_line(process, "recording /joint_states", lines, TIMEOUT), "".join(lines)
            probe.spin_until(lambda: publisher.get_subscription_count() >= 1)  # else the first are lost
            end = time.monotonic() + 0.3 + delay
            while time.monotonic() < end:
                k = len(published)
                publisher.publish(JointState(name=NAMES, position=[0.0] * 6, effort=[float(k)] * 6))
                published.append((time.monotonic(), k))
                time.sleep(PERIOD)
        first_signal = time.monotonic()
        for s, gap in zip(signals, gaps):
            process.send_signal(s)
            time.sleep(gap)
        output, _ = process.communicate(timeout=TIMEOUT)
    finally:
        process.kill()
    output = "".join(lines) + output
    assert process.returncode == 0, output
    assert "Traceback" not in output, output
    settled = [k for t, k in published if t < first_signal - SETTLED]
    if not out.exists():  # stopped before it created the bag, or before a message came: no bag
        assert phase != "recording" or not settled, output
        assert "nothing written" in output, output
        return
    efforts = readable(out)
    assert f"wrote {out}: {len(efforts)} messages" in output, output
    assert len(efforts), "a bag without a message is not left"
    assert np.all(np.diff(efforts) == 1.0), "a message lost or out of order"
    if settled:
        assert len(efforts) and efforts[0] <= settled[0] + 50 and efforts[-1] >= settled[-1], (settled[-1], output)
