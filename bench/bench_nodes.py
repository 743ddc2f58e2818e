"""Benchmark of the nodes over real DDS: id_node end to end against a relay, and the payload check.

    .venv/bin/python bench/bench_nodes.py [--duration 10] [--rates 1000 2000]
        [--executor events [single_threaded]] [--no-event-handlers] [--profile] [--no-payload] [--no-stream]
        [--change-period 0.1] [--no-changes]
    .venv/bin/python bench/bench_nodes.py --soak MINUTES

Prints one table and writes the raw figures to bench/results/nodes.json. Sections:

- end to end, per rate and executor: the node under test runs in its own process (id_node
  as ``python -m irb140_dynamics.id_node``, or the baseline bench/relay_node.py, which
  republishes joint_states unchanged on feedforward_torques with the same QoS). This
  process publishes JointState at a fixed rate for a warm-up and then ``--duration``
  seconds, each message stamped with the time it is published, and takes the torque
  messages as they arrive (id_node copies the input stamp into its output; the relay
  sends the message itself): delay = the DDS reception time of the output - the stamp.
  Lost = published in the measured window - received. CPU per message = the node
  process's user + system time over the window / messages published.
- parameter changes: the relay and id_node again at 1 kHz while payload.mass is set every
  ``--change-period`` s through the SetParameters service (bench/parameter_changes.py).
- soak (``--soak MINUTES``, alone): id_node and the relay side by side under the same load,
  their RSS growth (bench/soak.py, bench/results/soak.json).
- payload check: check_payload() cold (first call in a fresh process, kernel compilation
  included; the rated payload, and an off-axis one whose proof spends its budget) and warm,
  its two halves (derive_torque_limits, workspace_load) alone, and the round trip of a
  ``~/check`` service call on a running payload_check_node.

The script sets ROS_DOMAIN_ID (random in 50..99 unless --domain-id) and
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST for itself and the nodes it starts, and gives every
node its own namespace; nodes are stopped on exit whatever happens.
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import math
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

from common import (  # first: puts the checkout on sys.path
    REPO,
    RESULTS,
    Figure,
    NotMeasured,
    Row,
    machine_info,
    print_table,
    seconds_per_call,
    set_priority,
    write_results,
)
from irb140_dynamics.ros.spin import EXECUTORS  # noqa: E402  (events: what every node's main() uses)
from node_processes import QOS_DEPTH, NodeProcess, isolated_domain, node_command, wait_for  # noqa: E402
from parameter_changes import ParameterChanger  # noqa: E402
from soak import print_soak, soak  # noqa: E402
from stream_table import stream_rows  # noqa: E402

NAMES = [f"joint_{i}" for i in range(1, 7)]
CENTRE = np.array([0.0, -0.6, 1.0, 0.0, 0.5, 0.0])  # rad, as the demo node: every joint a sine
AMPLITUDE = np.array([0.8, 0.5, 0.5, 1.0, 0.6, 1.5])  # rad
PERIOD = np.array([8.0, 6.0, 5.0, 7.0, 4.0, 9.0])  # s

RATES = (1000, 2000)  # Hz
CHANGE_RATE = 1000  # Hz, of the run with parameter changes
CHANGE_PERIOD = 0.1  # s between two parameter changes in that run
DURATION = 10.0  # s measured, per run
WARMUP = 1.0  # s streamed before the measured window
REPEAT = 3  # runs of each pair (relay, id_node): one run's p99 moves 2-3x with this VM's stalls
RECEIVER_DEPTH = 5000  # this process's torque subscription: never the one that overflows
STARTUP_TIMEOUT = 30.0  # s, for a node process to start and match
DRAIN_TIMEOUT = 2.0  # s, for the last outputs after the last message published
QUIET = 0.3  # s without an output: the stream is over
OTHERS_WARNING = 0.25  # cores used by other processes during a run worth a note
STOLEN_WARNING = 1.0  # % of the CPUs' time taken by the hypervisor during a run worth a note
BENCH_SWITCH_INTERVAL = 1e-4  # s: how long the publishing thread may wait for the interpreter lock
# SCHED_FIFO priority of the publishing thread (as ros2_control's loop); BENCH_PRIORITY=0: normal
PUBLISHER_PRIORITY = int(os.environ.get("BENCH_PRIORITY", 50))

COLD_PROCESSES = 3  # fresh processes for the cold check_payload call
SERVICE_CALLS = 20  # ~/check calls after the first
SETTLE = 1.0  # s after ~/check appears before the first call: DDS discovery done
STRETCHED = [0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0]  # rad: the arm horizontal


# -- the end-to-end stream ------------------------------------------------------------------------


class Receiver(threading.Thread):
    """Takes the torque messages as they arrive, with their times, in a tight loop of its own.

    It waits on the subscription alone and takes every message ready (no executor): per
    message (input stamp, output's source time at the node, its DDS reception time here,
    the time taken here), all in ns of the system clock, and the output's sequence number
    at the node's writer (a gap: the node published it and it was lost on the way here).
    """

    def __init__(self, subscription, context):
        super().__init__(daemon=True)
        self.subscription, self.context = subscription, context
        self.records: list[tuple[int, int, int, int, int]] = []
        self.last_arrival = time.monotonic()
        self.stopping = threading.Event()

    def run(self) -> None:
        from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

        sub, records = self.subscription, self.records
        wait_set = _rclpy.WaitSet(1, 0, 0, 0, 0, 0, self.context.handle)
        while not self.stopping.is_set():
            wait_set.clear_entities()
            wait_set.add_subscription(sub.handle)
            wait_set.wait(10_000_000)  # ns
            while True:
                with sub.handle:
                    taken = sub.handle.take_message(sub.msg_type, sub.raw)
                if taken is None:
                    break
                now = time.time_ns()
                msg, info = taken
                stamp = msg.header.stamp
                records.append((stamp.sec * 1_000_000_000 + stamp.nanosec, info["source_timestamp"],
                                info["received_timestamp"], now, info["publication_sequence_number"] or 0))
                self.last_arrival = time.monotonic()

    def stop(self) -> None:
        self.stopping.set()
        self.join(timeout=5)


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


def machine_busy() -> tuple[int, int, int]:
    """(busy, total, stolen) jiffies of all CPUs so far, from /proc/stat; stolen: the time
    a virtual machine's CPUs were runnable but the hypervisor ran something else."""
    with open("/proc/stat") as stat:
        values = [int(x) for x in stat.readline().split()[1:]]
    idle = values[3] + values[4]  # idle, iowait
    steal = values[7] if len(values) > 7 else 0
    return sum(values) - idle - steal, sum(values), steal


def stream_run(node, kind: str, executor: str, rate: float, duration: float, warmup: float,
               env: dict, index: int, profile: bool = False, lean: bool = False,
               change_period: float | None = None, effort: bool = False) -> dict:
    """Start the node, stream joint states at ``rate`` through it, return the raw figures.

    ``effort``: every joint state carries efforts (id_node then runs its momentum observer
    and publishes external_torques too).
    ``profile``: py-spy samples the node over the measured window (bench/results/profile_*.txt).
    ``change_period``: set payload.mass (a new value each time) every that many seconds
    over the measured window, through the parameter service (see ParameterChanger).
    """
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    namespace = f"/bench_nodes_{os.getpid()}_{index}"
    process = NodeProcess(node_command(kind, executor, namespace, lean), env)
    publisher = subscription = receiver = spy = changer = None
    changes = None
    profile_path = RESULTS / f"profile_{kind}_{executor}_{rate:g}hz.txt"
    try:
        publisher = node.create_publisher(
            JointState, f"{namespace}/joint_states",
            QoSProfile(depth=QOS_DEPTH, reliability=ReliabilityPolicy.BEST_EFFORT))
        subscription = node.create_subscription(
            JointState, f"{namespace}/feedforward_torques", lambda msg: None,
            QoSProfile(depth=RECEIVER_DEPTH, reliability=ReliabilityPolicy.RELIABLE))
        wait_for(lambda: publisher.get_subscription_count() > 0
                 and node.count_publishers(f"{namespace}/feedforward_torques") > 0,
                 STARTUP_TIMEOUT, process, f"{kind} matched on joint_states and feedforward_torques")
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
                    cpu0, own0, busy0 = process.cpu_seconds(), time.process_time(), machine_busy()
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
                if (receiver.records and receiver.records[-1][0] == last) or time.monotonic() - receiver.last_arrival > QUIET:
                    break
                time.sleep(0.005)
        cpu = process.cpu_seconds() - cpu0
        own = time.process_time() - own0
        busy1 = machine_busy()
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
        if publisher is not None:
            node.destroy_publisher(publisher)
        process.stop()
    run = summarize(kind, executor, rate, duration, stamps[~skipped], first - int(skipped[:first].sum()),
                    lateness[~skipped], receiver.records, cpu, own, busy0, busy1, sent_s)
    # ticks of the window the source was too late for (a stall of this process): not sent,
    # as a driver's fixed-rate loop that overran sends its current state, not the missed ones
    run["stale_ticks_not_sent"] = int(skipped[first:].sum())
    run["source_late_max_ms"] = float(lateness[first:].max() * 1e3)
    run["qos_event_handlers"] = not lean
    run["parameter_changes"] = changes
    run["publisher_sched_fifo"] = realtime
    if profile:
        run["profile"] = {"file": str(profile_path.relative_to(REPO)), "top": profile_summary(profile_path)}
    return run


def start_profiler(process: NodeProcess, duration: float, path) -> subprocess.Popen:
    """py-spy sampling the node's Python stacks (not its idle threads) for ``duration`` s."""
    spy = Path(sys.executable).with_name("py-spy")
    if not spy.is_file():
        raise RuntimeError(f"--profile needs py-spy: {spy.parent}/pip install py-spy")
    RESULTS.mkdir(parents=True, exist_ok=True)
    return subprocess.Popen(
        [str(spy), "record", "--pid", str(process.process.pid), "--duration", f"{duration:g}",
         "--rate", "250", "--nonblocking", "--format", "raw", "--output", str(path)],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, preexec_fn=lambda: set_priority(0))


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


def percentiles(x_ns: np.ndarray) -> dict:
    """p50, p99, max (us) of delays in ns; None when there are none."""
    if x_ns.size == 0:
        return {"p50": None, "p99": None, "max": None}
    us = x_ns / 1e3
    return {"p50": float(np.percentile(us, 50)), "p99": float(np.percentile(us, 99)), "max": float(us.max())}


def summarize(kind, executor, rate, duration, stamps, first, lateness, records, cpu, own, busy0, busy1,
              sent_s) -> dict:
    measured = stamps[first:]
    sent = measured.size
    records = np.array(records, dtype=np.int64).reshape(-1, 5)
    if records.size:
        _, unique = np.unique(records[:, 0], return_index=True)
        records = records[np.sort(unique)]
    in_window = np.isin(records[:, 0], measured)
    window = records[in_window]
    stamp, source, received, taken, sequence = window.T
    received_count = int(window.shape[0])
    # outputs the node published in the window but that never arrived: gaps in its sequence
    published = int(sequence.max() - sequence.min() + 1) if received_count and sequence.min() > 0 else None
    warmup_stamps = stamps[:first]
    ticks = os.sysconf("SC_CLK_TCK")
    window_s = max(1e-9, (busy1[1] - busy0[1]) / ticks / (os.cpu_count() or 1))  # wall time
    busy_cores = (busy1[0] - busy0[0]) / ticks / window_s
    return {
        "node": kind,
        "executor": executor,
        "rate_hz": rate,
        "duration_s": duration,
        "sent": int(sent),
        "received": received_count,
        "lost": int(sent - received_count),
        # of the lost: published by the node (between the first and last received) but not
        # received here; the rest the node never published (dropped on the way in, or never taken)
        "lost_after_node_published": None if published is None else published - received_count,
        "lost_runs": lost_runs(measured, np.isin(measured, stamp), rate),
        # [time into the window (s), delay (ms)] of the outputs delayed most: where the stalls were
        "slowest": slowest(stamp, received, int(measured[0]) if sent else 0),
        "lost_in_warmup": int(first - np.isin(records[:, 0], warmup_stamps).sum()),
        # publish here -> DDS reception of the torques here: the figure of the table
        "delay_us": percentiles(received - stamp),
        # publish here -> taken by this process's receiving loop (what a Python consumer sees)
        "delay_taken_us": percentiles(taken - stamp),
        # publish here -> the node publishes the torques (its source timestamp)
        "delay_to_node_output_us": percentiles(source - stamp),
        "node_cpu_us_per_msg": cpu / sent * 1e6,
        "node_cpu_percent": cpu / duration * 100,
        "bench_cpu_percent": own / duration * 100,
        "machine_busy_percent": 100 * busy_cores / (os.cpu_count() or 1),
        # share of the CPUs' time the hypervisor gave to others (steal): stalls nobody here caused
        "stolen_percent": 100 * (busy1[2] - busy0[2]) / max(1, busy1[1] - busy0[1]),
        # CPU of everything else on the machine, in cores: not ours, not the node's
        "other_processes_cores": busy_cores - (cpu + own) / window_s,
        "achieved_rate_hz": sent / sent_s if sent_s > 0 else None,
        "send_lateness_us": {
            "p50": float(np.percentile(lateness[first:], 50) * 1e6),
            "p99": float(np.percentile(lateness[first:], 99) * 1e6),
            "max": float(lateness[first:].max() * 1e6),
        },
    }


def slowest(stamp: np.ndarray, received: np.ndarray, window_start: int, most: int = 20) -> list[list]:
    """[time into the window (s), delay (ms)] of the ``most`` outputs delayed most, in time order."""
    delay = received - stamp
    worst = np.sort(np.argsort(delay)[-most:]) if delay.size else []
    return [[round((int(stamp[k]) - window_start) / 1e9, 4), round(int(delay[k]) / 1e6, 2)] for k in worst]


def lost_runs(measured: np.ndarray, arrived: np.ndarray, rate: float, most: int = 20) -> list[list]:
    """Runs of consecutive lost messages: [time into the window (s), how many], the first ``most``."""
    runs, i = [], 0
    missing = np.flatnonzero(~arrived)
    while i < missing.size and len(runs) < most:
        j = i
        while j + 1 < missing.size and missing[j + 1] == missing[j] + 1:
            j += 1
        runs.append([round(float(missing[i]) / rate, 4), int(j - i + 1)])
        i = j + 1
    return runs


def end_to_end(rates, executors, duration, warmup, env, profile=False, lean=False,
               change_period: float | None = None, change_rate: float = CHANGE_RATE,
               effort: bool = False, repeat: int = 1) -> tuple[list[Row], list[dict]]:
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
                run = stream_run(node, kind, executor, rate, duration, warmup, env, len(runs), profile, lean,
                                 changes, effort)
                runs.append(run)
                d = run["delay_us"]
                print(f"    p50 {_opt(d['p50'])} us, p99 {_opt(d['p99'])} us, max {_opt(d['max'])} us, "
                      f"lost {run['lost']} of {run['sent']}, node CPU {run['node_cpu_us_per_msg']:.1f} us/msg, "
                      f"source late by up to {run['source_late_max_ms']:.1f} ms "
                      f"({run['stale_ticks_not_sent']} stale ticks not sent)", flush=True)
                if run["parameter_changes"] is not None:
                    c = run["parameter_changes"]
                    print(f"    changes: {c['accepted']} accepted, {c['refused']} refused, {c['unanswered']} "
                          f"unanswered; reply p50 {_opt(c['reply_ms']['p50'])} ms, p99 {_opt(c['reply_ms']['p99'])} ms",
                          flush=True)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return stream_rows(runs), runs


def _opt(x) -> str:
    return "-" if x is None else f"{x:.0f}"


# -- the payload check ----------------------------------------------------------------------------

COLD_SNIPPET = """
import math, time
from irb140_dynamics.core import RigidBody, check_payload, irb140
q = [0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0]
start = time.perf_counter()
check_payload(irb140(), RigidBody({payload}), q=q)
print(time.perf_counter() - start)
"""
OFF_AXIS = "3.0, (0.05, 0.0, 0.1)"  # a payload whose worst wrist poses form curves: the proof's budget is spent


def payload_rows(env: dict) -> tuple[list[Row], dict]:
    from irb140_dynamics.core import RigidBody, check_payload, derive_torque_limits, irb140, workspace_load

    group = "payload check (no baseline)"

    def cold(payload: str) -> list[float]:
        seconds = []
        for _ in range(COLD_PROCESSES):
            out = subprocess.run([sys.executable, "-c", COLD_SNIPPET.format(payload=payload)], env=env,
                                 capture_output=True, text=True, timeout=120, check=True)
            seconds.append(float(out.stdout.split()[-1]))
        return seconds

    model, payload = irb140(), RigidBody(6.0)
    limits = derive_torque_limits(model)
    timed = {
        "check_payload, cold: first call in a fresh process": cold("6.0"),
        f"check_payload, cold, RigidBody({OFF_AXIS})": cold(OFF_AXIS),
        "check_payload, warm": seconds_per_call(lambda: check_payload(model, payload, q=STRETCHED),
                                                blocks=7, block_seconds=0.2),
        "  derive_torque_limits alone": seconds_per_call(lambda: derive_torque_limits(model),
                                                         blocks=7, block_seconds=0.2),
        "  workspace_load (the sweep and its proof) alone": seconds_per_call(lambda: workspace_load(model, payload, limits),
                                                               blocks=7, block_seconds=0.2),
    }
    rows = [Row(group, name, Figure.cost(samples, "ms")) for name, samples in timed.items()]
    service, raw = service_calls(env)
    rows += [Row(group, name, figure) for name, figure in service]
    return rows, {**{name.strip(): samples for name, samples in timed.items()}, **raw}


def service_calls(env: dict) -> tuple[list[tuple[str, Figure]], dict]:
    """Round trips of ~/check on a payload_check_node process (see _time_service_calls)."""
    names = ("~/check round trip, first call",
             f"~/check round trip, next {SERVICE_CALLS} calls",
             "~/check round trip, new participant at once")
    if not (REPO / "irb140_dynamics" / "payload_check_node.py").is_file():
        reason = "payload_check_node missing"
        return [(name, NotMeasured(None, None, "ms", reason)) for name in names], {"service": reason}
    try:
        first, rest, at_discovery = _time_service_calls(env)
    except Exception as error:  # noqa: BLE001 - a node that does not work yet is a result too
        reason = str(error).splitlines()[0]
        print(f"  ~/check not measured: {error}", flush=True)
        return [(name, NotMeasured(None, None, "ms", reason)) for name in names], {"service": reason}
    figures = (Figure.cost([first], "ms"), Figure.cost(rest, "ms"), Figure.cost([at_discovery], "ms"))
    return list(zip(names, figures)), {
        "service_first_call_s": first,
        "service_next_calls_s": rest,
        "service_new_participant_first_call_s": at_discovery,
    }


def _time_service_calls(env: dict) -> tuple[float, list[float], float]:
    """On a fresh payload_check_node process: a client's first call, made once discovery has
    settled (SETTLE s after the service appeared), and its next calls; then a client in a
    new DDS participant (as `ros2 service call` has) calling the moment it sees the service,
    which includes the server's wait for its reply path to this participant to match."""
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from std_srvs.srv import Trigger

    namespace = f"/bench_nodes_{os.getpid()}_payload"
    process = NodeProcess([sys.executable, "-m", "irb140_dynamics.payload_check_node",
                           "--ros-args", "-r", f"__ns:={namespace}"], env)

    def calls(settle: float, count: int) -> list[float]:
        """A client in a participant of its own: wait for the service, settle, call."""
        context = Context()
        rclpy.init(context=context)
        node = executor = None
        try:
            node = Node("bench_nodes_client", context=context)
            executor = SingleThreadedExecutor(context=context)
            executor.add_node(node)
            client = node.create_client(Trigger, f"{namespace}/payload_check_node/check")
            wait_for(client.service_is_ready, STARTUP_TIMEOUT, process, "payload_check_node's ~/check")
            time.sleep(settle)
            times = []
            for _ in range(count):
                start = time.perf_counter()
                future = client.call_async(Trigger.Request())
                executor.spin_until_future_complete(future, timeout_sec=10.0)
                if not future.done():
                    raise process.fail("~/check: no reply within 10 s")
                if not future.result().message:
                    raise process.fail("~/check: an empty reply")
                times.append(time.perf_counter() - start)
            return times
        finally:
            if executor is not None:
                executor.shutdown(timeout_sec=1.0)
            if node is not None:
                node.destroy_node()
            rclpy.try_shutdown(context=context)

    try:
        settled = calls(SETTLE, 1 + SERVICE_CALLS)
        at_discovery = calls(0.0, 1)
        return settled[0], settled[1:], at_discovery[0]
    finally:
        process.stop()


# -- main -----------------------------------------------------------------------------------------


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=DURATION, help="measured seconds per run (default 10)")
    parser.add_argument("--warmup", type=float, default=WARMUP, help="seconds streamed before measuring (default 1)")
    parser.add_argument("--rates", type=float, nargs="+", default=list(RATES), help="Hz (default 1000 2000)")
    parser.add_argument("--executor", nargs="+", choices=EXECUTORS, default=["events"],
                        help="executor of both nodes: events (rclpy.experimental.EventsExecutor, as "
                             "main() does; default) and/or single_threaded (rclpy.spin)")
    parser.add_argument("--no-event-handlers", action="store_true",
                        help="run both nodes without rclpy's default QoS event handlers "
                             "(a bench-only variant through relay_node.py)")
    parser.add_argument("--no-payload", action="store_true", help="skip the payload check section")
    parser.add_argument("--change-period", type=float, default=CHANGE_PERIOD,
                        help=f"s between two payload.mass changes in the run at {CHANGE_RATE} Hz with parameter "
                             f"changes (default {CHANGE_PERIOD:g})")
    parser.add_argument("--no-changes", action="store_true", help="skip the run with parameter changes")
    parser.add_argument("--repeat", type=int, default=REPEAT,
                        help=f"runs of each pair, relay and id_node in turn; the table shows medians and total "
                             f"losses (default {REPEAT})")
    parser.add_argument("--soak", type=float, metavar="MINUTES", default=None,
                        help="only the soak: id_node and the relay side by side at 1 kHz for MINUTES "
                             "(10 in the issue), their RSS growth (bench/results/soak.json)")
    parser.add_argument("--no-stream", action="store_true", help="skip the end-to-end section")
    parser.add_argument("--effort", action="store_true",
                        help="joint states carry efforts: id_node's momentum observer runs on every message")
    parser.add_argument("--profile", action="store_true",
                        help="sample each node with py-spy over the measured window "
                             "(bench/results/profile_*.txt; perturbs the figures a little)")
    parser.add_argument("--domain-id", type=int, default=None, help="ROS_DOMAIN_ID (default: random in 50..99)")
    return parser.parse_args(argv)


def main(argv=None) -> None:
    args = parse_args(argv)
    started = time.perf_counter()
    domain_id, env = isolated_domain(args.domain_id)
    if args.soak is not None:
        results = soak(args.soak, CHANGE_RATE, env)
        print_soak(results)
        path = write_results("soak", {"benchmark": "soak", "machine": machine_info(("numpy", "rclpy")), **results,
                                      "runtime_s": time.perf_counter() - started})
        print(f"raw figures: {path.relative_to(REPO)}")
        return

    rows, runs, payload = [], [], {}
    if not args.no_stream:
        stream, runs = end_to_end(args.rates, args.executor, args.duration, args.warmup, env, args.profile,
                                  args.no_event_handlers, None if args.no_changes else args.change_period,
                                  effort=args.effort, repeat=args.repeat)
        rows += stream
    if not args.no_payload:
        print("  payload check ...", flush=True)
        payload_table, payload = payload_rows(env)
        rows += payload_table
    observer = "; joint states with efforts: observer on" if args.effort else ""
    print_table(rows, f"irb140_dynamics nodes (ratio = ours / baseline; delays: publish -> torques received{observer})")
    busy = [r for r in runs if r["other_processes_cores"] > OTHERS_WARNING]
    if busy:
        worst = max(r["other_processes_cores"] for r in busy)
        print(f"note: other processes used up to {worst:.2f} of {os.cpu_count()} cores during "
              f"{len(busy)} of {len(runs)} runs: the delays and losses are not those of an idle machine")
    stolen = [r for r in runs if r["stolen_percent"] > STOLEN_WARNING]
    if stolen:
        print(f"note: the hypervisor took up to {max(r['stolen_percent'] for r in stolen):.1f} % of the CPUs' time "
              f"(steal) during {len(stolen)} of {len(runs)} runs: stalls of a shared host, not of these processes")
    if args.profile:
        print("profiled (py-spy): figures perturbed; share of the node's samples, inclusive:")
        for r in runs:
            top = ", ".join(f"{name} {share:g}%" for name, share in r.get("profile", {}).get("top", [])[:8])
            print(f"  {r['node']} {r['rate_hz']:g} Hz {r['executor']}: {top}")
    name = "nodes_effort" if args.effort else "nodes"
    path = write_results(
        name,
        {
            "benchmark": name,
            "machine": machine_info(("numpy", "rclpy")),
            "settings": {
                "duration_s": args.duration,
                "warmup_s": args.warmup,
                "rates_hz": args.rates,
                "executors": args.executor,
                "qos": {"joint_states": f"best_effort, depth {QOS_DEPTH}",
                        "feedforward_torques": f"reliable, depth {QOS_DEPTH} (node) / {RECEIVER_DEPTH} (here)"},
                "rmw": os.environ.get("RMW_IMPLEMENTATION", "default (rmw_fastrtps_cpp)"),
                "ros_domain_id": domain_id,
                "profiled": args.profile,
                "efforts": args.effort,
                "repeat": args.repeat,
                "qos_event_handlers": not args.no_event_handlers,
            },
            "rows": [row.as_dict() for row in rows],
            "runs": runs,
            "payload_raw_s": payload,
            "runtime_s": time.perf_counter() - started,
        },
    )
    print(f"raw figures: {path.relative_to(REPO)} ({time.perf_counter() - started:.0f} s)")


if __name__ == "__main__":
    main()
