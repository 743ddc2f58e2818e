"""record, the bag recorder for installs without rosbag2, as its own process: it waits for
the topic, takes its type from the graph, adapts to a best-effort publisher, stops after
--duration, and writes a bag that `identify` reads; an existing bag is refused in one line;
a topic nobody publishes: the topics that have a publisher named, and no bag left."""

import os
import signal
import stat
import sys
import time

import numpy as np
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

from irb140_dynamics.identification.recording import Recording

from ..support.node_process import TIMEOUT, run_to_exit, start, wait_for_line

NAMES = [f"joint_{i}" for i in range(1, 7)]
RATE = 200.0  # Hz


def record_command(out, *options):
    return [sys.executable, "-m", "irb140_dynamics.tools.record", "--out", str(out), *options]


def test_record_writes_what_was_published_for_the_duration(probe, tmp_path):  # noqa: F811
    out = tmp_path / "run"
    process = start(record_command(out, "--duration", "0.5"))
    best_effort = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
    publisher = probe.create_publisher(JointState, "joint_states", best_effort)
    deadline, k = time.monotonic() + TIMEOUT, 0
    try:
        while process.poll() is None:
            assert time.monotonic() < deadline, "record did not stop"
            msg = JointState(name=NAMES, position=[k * 1e-3] * 6, velocity=[1.0] * 6, effort=[float(k)] * 6)
            msg.header.stamp.sec, msg.header.stamp.nanosec = 1000 + k // 200, (k % 200) * 5_000_000
            publisher.publish(msg)
            k += 1
            time.sleep(1.0 / RATE)
        output = process.stdout.read()
    finally:
        process.kill()
    assert process.returncode == 0, output
    assert "recording /joint_states (sensor_msgs/msg/JointState, best effort)" in output, output
    chunks = list(Recording(out, NAMES).chunks())
    effort = np.concatenate([chunk.effort for chunk in chunks])[:, 0]
    time_ = np.concatenate([chunk.time for chunk in chunks])
    assert f"wrote {out}: {len(effort):,} messages of /joint_states" in output
    mask = os.umask(0o022)  # the umask record inherited (read back at once)
    os.umask(mask)
    written = {p.name: stat.S_IMODE(p.stat().st_mode) for p in [out, *out.iterdir()]}
    assert written == {p: (0o777 if p == out.name else 0o666) & ~mask for p in written}, written  # as the umask says
    assert 10 < len(effort) < 0.5 * RATE * 1.2  # 0.5 s of a 200 Hz stream (slower when the machine is busy)
    assert np.all(np.diff(effort) == 1.0)  # every message, in order, none lost
    np.testing.assert_allclose(np.diff(time_), 0.005, atol=1e-9)  # the header stamps
    np.testing.assert_allclose(np.concatenate([c.position for c in chunks])[:, 0], effort * 1e-3)

    code, output = run_to_exit(record_command(out))
    assert code == 1 and "exists already" in output and "Traceback" not in output, output


def test_record_stops_by_itself_after_the_reference_motion_not_at_a_hold(probe, tmp_path):  # noqa: F811
    from builtin_interfaces.msg import Duration
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

    out = tmp_path / "run"
    process = start(record_command(out, "--reference", "/ref", "--tail", "0.2"))
    states = probe.create_publisher(JointState, "joint_states", 10)
    reference = probe.create_publisher(JointTrajectory, "/ref", 10)
    hold = JointTrajectory(joint_names=NAMES, points=[JointTrajectoryPoint(positions=[0.0] * 6)])
    motion = JointTrajectory(
        joint_names=NAMES,
        points=[JointTrajectoryPoint(positions=[0.0] * 6), JointTrajectoryPoint(positions=[0.1] * 6)],
    )
    motion.points[1].time_from_start = Duration(sec=0, nanosec=300_000_000)
    lines, k, held = [], 0, None
    deadline = time.monotonic() + TIMEOUT
    os.set_blocking(process.stdout.fileno(), False)
    try:
        while process.poll() is None:
            while line := process.stdout.readline():
                lines.append(line)
            assert time.monotonic() < deadline, "record did not stop"
            states.publish(JointState(name=NAMES, position=[0.0] * 6, effort=[float(k)] * 6))
            k += 1
            if reference.get_subscription_count() and held is None:
                reference.publish(hold)  # a hold is no motion: record goes on
                held = time.monotonic()
            elif held is not None and time.monotonic() > held + 1.0 and not any("following" in x for x in lines):
                reference.publish(motion)  # until record has it (unstamped: it starts at its last arrival)
            time.sleep(1.0 / RATE)
        output = "".join(lines) + (process.stdout.read() or "")
    finally:
        process.kill()
    assert process.returncode == 0, output
    assert "following /ref: stops 0.2 s after its motion ends (0.3 s long)" in output, output
    assert "stopped: 0.2 s after the end of the motion on /ref" in output, output
    effort = np.concatenate([chunk.effort for chunk in Recording(out, NAMES).chunks()])[:, 0]
    assert f"wrote {out}: {len(effort)} messages" in output and np.all(np.diff(effort) == 1.0)


def test_a_topic_nobody_publishes_names_those_published_and_leaves_no_bag(probe, tmp_path):  # noqa: F811
    """`record --topic /nosuch`: one line naming the topics that have a publisher (here the
    probe's /joint_states; not every node's /rosout), still waiting; Ctrl-C: no bag, exit 0."""
    probe.create_publisher(JointState, "joint_states", 10)
    out = tmp_path / "run"
    process = start(record_command(out, "--topic", "/nosuch"))
    lines: list[str] = []
    try:
        assert wait_for_line(process, "still waiting for /nosuch", lines, TIMEOUT), "".join(lines)
        assert process.poll() is None, "".join(lines)  # it waits on: the publisher may start later
        process.send_signal(signal.SIGINT)
        rest, _ = process.communicate(timeout=TIMEOUT)
    finally:
        process.kill()
    output = "".join(lines) + rest
    named = [line for line in lines if "still waiting" in line]
    assert len(named) == 1 and "no publisher of /nosuch; topics with one: " in named[0], output
    assert "/joint_states (sensor_msgs/msg/JointState)" in named[0] and "/rosout" not in named[0], output
    assert process.returncode == 0 and "Traceback" not in output, output
    assert "no message came on /nosuch: nothing written" in output and not out.exists(), output
