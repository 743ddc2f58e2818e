"""The end-to-end stream of bench_nodes.py: a node under test in its own process, joint states
streamed through it at a fixed rate from this process, its torques taken back here.

Delay = the DDS reception time of an output here - the stamp of its input (this process
stamps each joint state with the time it publishes it; id_node copies the input stamp into
its output, the relay sends the message itself). Lost = published in the measured window -
received. CPU per message = the node process's user + system time over the window /
messages published.
"""

from __future__ import annotations

import contextlib
import gc
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from common import RESULTS, Row, set_priority, shown  # first: puts the checkout on sys.path
from machine_load import load_between, snapshot
from node_processes import QOS_DEPTH, STARTUP_TIMEOUT, NodeProcess, node_command, wait_for
from parameter_changes import ParameterChanger
from receiver import Receiver
from stream_stats import summarize
from stream_table import stream_rows

NAMES = [f"joint_{i}" for i in range(1, 7)]
CENTRE = np.array([0.0, -0.6, 1.0, 0.0, 0.5, 0.0])  # rad, as the demo node: every joint a sine
AMPLITUDE = np.array([0.8, 0.5, 0.5, 1.0, 0.6, 1.5])  # rad
PERIOD = np.array([8.0, 6.0, 5.0, 7.0, 4.0, 9.0])  # s

CHANGE_RATE = 1000  # Hz, of the run with parameter changes
RECEIVER_DEPTH = 5000  # this process's torque subscription: never the one that overflows
DRAIN_TIMEOUT = 2.0  # s, for the last outputs after the last message published
QUIET = 0.3  # s without an output: the stream is over
BENCH_SWITCH_INTERVAL = 1e-4  # s: how long the publishing thread may wait for the interpreter lock
# SCHED_FIFO priority of the publishing thread (as ros2_control's loop); BENCH_PRIORITY=0: normal
PUBLISHER_PRIORITY = int(os.environ.get("BENCH_PRIORITY", 50))


@contextlib.contextmanager
def steady_publisher():
    """This process as a steady source while streaming, as a driver's real-time thread is:
    after a stall, late messages would leave in a burst that overflows any depth-10 queue,
    and the loss would be the benchmark's, not the node's (stream_run sends no tick whose
    successor is due already: a driver's loop that overran sends its current state). So no garbage-collector pass (one over the stream's
    ~100,000 lists and records takes tens of ms); the publishing thread waits at most
    BENCH_SWITCH_INTERVAL for the interpreter lock held by the receiving and
    parameter-changing threads; and it runs on SCHED_FIFO at PUBLISHER_PRIORITY when
    allowed (yields whether it does), so that the scheduler does not hold it back for a
    time slice (~4 ms) behind the node and this process's other threads."""
    interval = sys.getswitchinterval()
    gc.collect()
    gc.freeze()
    gc.disable()
    sys.setswitchinterval(BENCH_SWITCH_INTERVAL)
    realtime = bool(PUBLISHER_PRIORITY) and set_priority(PUBLISHER_PRIORITY)
    try:
        yield realtime
    finally:
        if realtime:
            set_priority(0)
        sys.setswitchinterval(interval)
        gc.enable()
        gc.unfreeze()


def joint_stream(count: int, rate: float) -> tuple[list, list]:
    """Positions and velocities (lists) of ``count`` samples of the moving arm."""
    t = np.arange(count)[:, None] / rate
    w = 2 * np.pi / PERIOD
    return (CENTRE + AMPLITUDE * np.sin(w * t)).tolist(), (AMPLITUDE * w * np.cos(w * t)).tolist()


def joint_efforts(positions: list, velocities: list) -> list:
    """Efforts a driver would publish along the stream: the model's torques at qdd = 0."""
    from irb140_dynamics.core import irb140, rnea_batch

    Q = np.array(positions)
    return rnea_batch(irb140(), Q, np.array(velocities), np.zeros_like(Q)).tolist()


def stream_run(
    node,
    kind: str,
    executor: str,
    rate: float,
    duration: float,
    warmup: float,
    env: dict,
    index: int,
    profile: bool = False,
    lean: bool = False,
    change_period: float | None = None,
    effort: bool = False,
    depth: int = QOS_DEPTH,
    listen: tuple[type, str] | None = None,
) -> dict:
    """Start the node, stream joint states at ``rate`` through it, return the raw figures.

    ``effort``: every joint state carries efforts (id_node then runs its momentum observer
    and publishes external_torques too).
    ``listen``: (message type, topic under the node's namespace) subscribed here too, as a
    viewer would (RViz for ~/markers): id_node builds what nobody subscribes to not at all.
    ``profile``: py-spy samples the node over the measured window (bench/results/profile_*.txt).
    ``change_period``: set payload.mass (a new value each time) every that many seconds
    over the measured window, through the parameter service (see ParameterChanger).
    """
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    namespace = f"/bench_nodes_{os.getpid()}_{index}"
    process = NodeProcess(node_command(kind, executor, namespace, lean, depth), env)
    publisher = subscription = receiver = spy = changer = viewer = None
    changes = None
    profile_path = RESULTS / f"profile_{kind}_{executor}_{rate:g}hz.txt"
    try:
        publisher = node.create_publisher(
            JointState,
            f"{namespace}/joint_states",
            QoSProfile(depth=QOS_DEPTH, reliability=ReliabilityPolicy.BEST_EFFORT),
        )
        subscription = node.create_subscription(
            JointState,
            f"{namespace}/feedforward_torques",
            lambda msg: None,
            QoSProfile(depth=RECEIVER_DEPTH, reliability=ReliabilityPolicy.RELIABLE),
        )
        if listen is not None:  # its messages are left in its queue: never taken, as cheap as can be here
            viewer = node.create_subscription(listen[0], f"{namespace}/{listen[1]}", lambda msg: None, 10)
        wait_for(
            lambda: (
                publisher.get_subscription_count() > 0
                and node.count_publishers(f"{namespace}/feedforward_torques") > 0
                and (viewer is None or viewer.get_publisher_count() > 0)
            ),
            STARTUP_TIMEOUT,
            process,
            f"{kind} matched on joint_states and feedforward_torques",
        )
        receiver = Receiver(subscription, node.context)
        receiver.start()
        if change_period is not None:
            changer = ParameterChanger(f"{namespace}/{kind}", change_period)
        with steady_publisher() as realtime:
            first = round(warmup * rate)
            total = first + round(duration * rate)
            positions, velocities = joint_stream(total, rate)
            efforts = joint_efforts(positions, velocities) if effort else None
            stamps = np.zeros(total, dtype=np.int64)
            lateness = np.zeros(total)
            skipped = np.zeros(total, dtype=bool)
            msg = JointState(name=NAMES)
            period = 1.0 / rate
            clock, sleep, now_ns = time.perf_counter, time.sleep, time.time_ns
            start = clock() + 0.01
            for i in range(total):
                deadline = start + i * period
                if i == first:  # the measured window starts
                    cpu0, own0, load0 = process.cpu_seconds(), time.process_time(), snapshot()
                    if profile:
                        spy = start_profiler(process, duration, profile_path)
                    if changer is not None:
                        changer.start()
                remaining = deadline - clock()
                if remaining > 0:  # no busy-wait: its CPU would be taken from the node under test
                    sleep(remaining)
                elif -remaining > period:  # the next tick is due too: this state is stale, not sent
                    skipped[i], lateness[i] = True, -remaining
                    continue
                msg.position, msg.velocity = positions[i], velocities[i]
                if efforts is not None:
                    msg.effort = efforts[i]
                stamp = now_ns()
                msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
                lateness[i] = clock() - deadline
                publisher.publish(msg)
                stamps[i] = stamp
            sent_s = clock() - start - first * period
            if changer is not None:
                changes, changer = changer.stop(), None

            last = int(stamps[-1])
            drain_end = time.monotonic() + DRAIN_TIMEOUT
            while time.monotonic() < drain_end:  # until the last output is in, or the stream is quiet
                if (
                    receiver.records and receiver.records[-1][0] == last
                ) or time.monotonic() - receiver.last_arrival > QUIET:
                    break
                time.sleep(0.005)
        cpu = process.cpu_seconds() - cpu0
        own = time.process_time() - own0
        load = load_between(load0, snapshot(), {os.getpid(), process.process.pid})
        if not process.alive():
            raise process.fail(f"{kind} died during the run")
    finally:
        if changer is not None:
            changer.stop() if changer.is_alive() else changer.close()
        if receiver is not None:
            receiver.stop()
        if spy is not None:
            try:
                spy.wait(timeout=duration + 10)
            except subprocess.TimeoutExpired:
                spy.kill()
                spy.wait(timeout=5)
        if subscription is not None:
            node.destroy_subscription(subscription)
        if viewer is not None:
            node.destroy_subscription(viewer)
        if publisher is not None:
            node.destroy_publisher(publisher)
        process.stop()
    run = summarize(
        kind,
        executor,
        rate,
        duration,
        stamps[~skipped],
        first - int(skipped[:first].sum()),
        lateness[~skipped],
        receiver.records,
        cpu,
        own,
        load,
        sent_s,
    )
    # ticks of the window the source was too late for (a stall of this process): not sent,
    # as a driver's fixed-rate loop that overran sends its current state, not the missed ones
    run["stale_ticks_not_sent"] = int(skipped[first:].sum())
    run["source_late_max_ms"] = float(lateness[first:].max() * 1e3)
    run["qos_event_handlers"] = not lean
    run["qos_depth"] = depth
    run["parameter_changes"] = changes
    run["publisher_sched_fifo"] = realtime
    if profile:
        run["profile"] = {"file": str(shown(profile_path)), "top": profile_summary(profile_path)}
    return run


def end_to_end(
    rates,
    executors,
    duration,
    warmup,
    env,
    profile=False,
    lean=False,
    change_period: float | None = None,
    change_rate: float = CHANGE_RATE,
    effort: bool = False,
    repeat: int = 1,
    depth: int = QOS_DEPTH,
) -> tuple[list[Row], list[dict]]:
    """Per executor and rate: the relay, then id_node, each in a fresh process, ``repeat``
    times in turn; then, with ``change_period``, both again at ``change_rate`` with a
    parameter change every ``change_period`` s."""
    import rclpy
    from rclpy.node import Node

    rclpy.init()
    node = Node("bench_nodes_load")
    runs = []
    plan = [(executor, rate, None) for executor in executors for rate in rates]
    if change_period is not None:
        plan.append((executors[0], change_rate, change_period))
    try:
        for executor, rate, changes in plan:
            for kind in ("relay", "id_node") * repeat:
                every = "" if changes is None else f", payload.mass set every {changes * 1e3:g} ms"
                print(f"  {kind} at {rate:g} Hz, {executor}{every}: {warmup + duration:g} s ...", flush=True)
                run = stream_run(
                    node, kind, executor, rate, duration, warmup, env, len(runs), profile, lean, changes, effort, depth
                )
                runs.append(run)
                d = run["delay_us"]
                print(
                    f"    p50 {_opt(d['p50'])} us, p99 {_opt(d['p99'])} us, max {_opt(d['max'])} us, "
                    f"lost {run['lost']} of {run['sent']}, node CPU {run['node_cpu_us_per_msg']:.1f} us/msg, "
                    f"source late by up to {run['source_late_max_ms']:.1f} ms "
                    f"({run['stale_ticks_not_sent']} stale ticks not sent)",
                    flush=True,
                )
                if run["parameter_changes"] is not None:
                    c = run["parameter_changes"]
                    print(
                        f"    changes: {c['accepted']} accepted, {c['refused']} refused, {c['unanswered']} "
                        f"unanswered; reply p50 {_opt(c['reply_ms']['p50'])} ms, p99 {_opt(c['reply_ms']['p99'])} ms",
                        flush=True,
                    )
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return stream_rows(runs), runs


def _opt(x) -> str:
    return "-" if x is None else f"{x:.0f}"


def start_profiler(process: NodeProcess, duration: float, path) -> subprocess.Popen:
    """py-spy sampling the node's Python stacks (not its idle threads) for ``duration`` s."""
    spy = Path(sys.executable).with_name("py-spy")
    if not spy.is_file():
        raise RuntimeError(f"--profile needs py-spy: {spy.parent}/pip install py-spy")
    RESULTS.mkdir(parents=True, exist_ok=True)
    return subprocess.Popen(
        [
            str(spy),
            "record",
            "--pid",
            str(process.process.pid),
            "--duration",
            f"{duration:g}",
            "--rate",
            "250",
            "--nonblocking",
            "--format",
            "raw",
            "--output",
            str(path),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        preexec_fn=lambda: set_priority(0),
    )


def profile_summary(path, top: int = 15) -> list[tuple[str, float]]:
    """The functions with the largest share of the samples (inclusive), from py-spy's raw
    output (collapsed stacks: 'frame;frame;... count')."""
    try:
        lines = Path(path).read_text().splitlines()
    except OSError:
        return []
    inclusive, total = {}, 0
    for line in lines:
        stack, _, count = line.rpartition(" ")
        if not stack:
            continue
        total += int(count)
        for frame in set(stack.split(";")):
            name = frame.split(" (")[0] + " (" + frame.split(" (")[-1].split(":")[0].rsplit("/", 1)[-1] + ")"
            inclusive[name] = inclusive.get(name, 0) + int(count)
    ranked = sorted(inclusive.items(), key=lambda item: -item[1])[:top]
    return [(name, round(100 * count / total, 1)) for name, count in ranked] if total else []
