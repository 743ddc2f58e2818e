"""The soak: id_node and the relay side by side under the same load for minutes, their memory.

id_node, id_node again with ``--disable-rosout-logs`` (id_node_quiet: what id_node itself
holds, without rcl's /rosout history, see below) and the relay run as their own processes,
in namespaces of their own; this process publishes the same JointState stream to each at
``rate`` (the moving arm; 1 % of the messages with a
NaN position, which id_node drops, and 1 % with an extra joint of a name never seen before,
which it ignores), takes their outputs, and sets payload.mass on each every
``change_period`` s. The anonymous resident memory (RssAnon: heap and stacks; VmRSS
also counts the pages of mapped files, which the kernel drops and reads back as it likes,
at the same instants in every process) of each is sampled every
``sample_period`` s; growth is given in kB per minute as the least-squares slope over the
whole run and over its second half (after start-up allocations have settled), after a
warm-up that is not counted.

The log messages each node sends to /rosout are counted too: rcl keeps the last 1,000 of a
node's log messages for late joiners (/rosout is transient local, depth 1000), about
0.5 kB each, so a node that warns (id_node, throttled, about the 1 % bad messages) grows
by that until it has logged 1,000 messages, then stops; the relay logs nothing.
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
import time

import numpy as np
from node_processes import QOS_DEPTH, STARTUP_TIMEOUT, NodeProcess, node_command, rss_kb, wait_for
from parameter_changes import ParameterChanger

NAMES = [f"joint_{i}" for i in range(1, 7)]
KINDS = ("id_node", "id_node_quiet", "relay")  # id_node_quiet: id_node with --disable-rosout-logs
WARMUP = 30.0  # s streamed before the first RSS sample that counts
SAMPLE_PERIOD = 10.0  # s
CHANGE_PERIOD = 5.0  # s, as in the issue's soak
TOLERANCE = 5.0  # kB/min: slopes closer than this are the same (page-granular noise)


class Drain(threading.Thread):
    """Takes every message of a subscription and counts it, nothing kept."""

    def __init__(self, subscription, context):
        super().__init__(daemon=True)
        self.subscription, self.context, self.count = subscription, context, 0
        self.stopping = threading.Event()

    def run(self) -> None:
        from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

        sub = self.subscription
        wait_set = _rclpy.WaitSet(1, 0, 0, 0, 0, 0, self.context.handle)
        while not self.stopping.is_set():
            wait_set.clear_entities()
            wait_set.add_subscription(sub.handle)
            wait_set.wait(50_000_000)
            while True:
                with sub.handle:
                    if sub.handle.take_message(sub.msg_type, sub.raw) is None:
                        break
                self.count += 1

    def stop(self) -> None:
        self.stopping.set()
        self.join(timeout=5)


def slope_kb_per_min(t_s: np.ndarray, rss: np.ndarray) -> float | None:
    if t_s.size < 2:
        return None
    return float(np.polyfit(t_s / 60.0, rss, 1)[0])


def soak(
    minutes: float,
    rate: float,
    env: dict,
    change_period: float = CHANGE_PERIOD,
    sample_period: float = SAMPLE_PERIOD,
    warmup: float = WARMUP,
    odd: bool = True,
) -> dict:
    """Run the soak; the raw figures (samples, slopes, messages) by node. ``odd``: with the
    1 % bad messages and 1 % of never-seen joint names."""
    import rclpy
    from rcl_interfaces.msg import Log
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    rclpy.init()
    node = Node("bench_soak_load")
    processes, publishers, drains, changers = {}, {}, {}, {}
    logs = {kind: 0 for kind in KINDS}

    def count_log(msg) -> None:
        for kind in KINDS:
            if msg.name.endswith(f"_{kind}.{kind.removesuffix('_quiet')}"):  # /bench_soak_<pid>_<kind>/<node>
                logs[kind] += 1

    node.create_subscription(Log, "/rosout", count_log, QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    spinner = threading.Thread(target=lambda: _spin(node), daemon=True)
    try:
        for kind in KINDS:
            namespace = f"/bench_soak_{os.getpid()}_{kind}"
            command = node_command(kind.removesuffix("_quiet"), "events", namespace)
            if kind.endswith("_quiet"):
                command.append("--disable-rosout-logs")  # its log messages to the console only
            processes[kind] = NodeProcess(command, env)
            publishers[kind] = node.create_publisher(
                JointState,
                f"{namespace}/joint_states",
                QoSProfile(depth=QOS_DEPTH, reliability=ReliabilityPolicy.BEST_EFFORT),
            )
            subscription = node.create_subscription(
                JointState,
                f"{namespace}/feedforward_torques",
                lambda msg: None,
                QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE),
            )
            wait_for(
                lambda: (
                    publishers[kind].get_subscription_count() > 0
                    and node.count_publishers(f"{namespace}/feedforward_torques") > 0
                ),
                STARTUP_TIMEOUT,
                processes[kind],
                f"{kind} matched",
            )
            drains[kind] = Drain(subscription, node.context)
            drains[kind].start()
            changers[kind] = ParameterChanger(f"{namespace}/{kind.removesuffix('_quiet')}", change_period)
        for changer in changers.values():
            changer.start()
        spinner.start()

        samples = {kind: [] for kind in KINDS}
        sent = 0
        msg, odd = JointState(), JointState()
        period = 1.0 / rate
        total_s = warmup + 60.0 * minutes
        start = time.perf_counter()
        next_sample = start + warmup
        w = [2 * math.pi / p for p in (8.0, 6.0, 5.0, 7.0, 4.0, 9.0)]
        print(f"  soak: {minutes:g} min at {rate:g} Hz after {warmup:g} s warm-up ...", flush=True)
        while True:
            now = time.perf_counter()
            if now - start > total_s:
                break
            if now >= next_sample:
                for kind in KINDS:
                    if not processes[kind].alive():
                        raise processes[kind].fail(f"{kind} died during the soak")
                    samples[kind].append((now - start - warmup, rss_kb(processes[kind].process.pid, "RssAnon")))
                next_sample += sample_period
            t = sent * period
            q = [0.5 * math.sin(wi * t) for wi in w]
            qd = [0.5 * wi * math.cos(wi * t) for wi in w]
            if odd and sent % 100 == 37:  # a bad message: dropped by id_node
                q[1] = math.nan
            if odd and sent % 100 == 71:  # a joint never seen before: ignored by id_node
                odd.name, odd.position, odd.velocity = NAMES + [f"tool_{sent}"], q + [0.0], qd + [0.0]
                out = odd
            else:
                msg.name, msg.position, msg.velocity = NAMES, q, qd
                out = msg
            stamp = time.time_ns()
            out.header.stamp.sec, out.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
            for publisher in publishers.values():
                publisher.publish(out)
            sent += 1
            remaining = start + sent * period - time.perf_counter()
            if remaining > 0:
                time.sleep(remaining)
        results = {}
        for kind in KINDS:
            changes = changers[kind].stop()
            t, rss = (np.array(x, dtype=float) for x in zip(*samples[kind])) if samples[kind] else (np.zeros(0),) * 2
            half = t >= t[-1] / 2 if t.size else t
            results[kind] = {
                "rss_anon_kb": samples[kind],
                "growth_kb": float(rss[-1] - rss[0]) if rss.size else None,
                "slope_kb_per_min": slope_kb_per_min(t, rss),
                "slope_second_half_kb_per_min": slope_kb_per_min(t[half], rss[half]),
                "outputs": drains[kind].count,
                "parameter_changes": changes,
                "log_messages": logs[kind],
            }
        results["sent"] = sent
        results["settings"] = {
            "minutes": minutes,
            "rate_hz": rate,
            "warmup_s": warmup,
            "sample_period_s": sample_period,
            "change_period_s": change_period,
        }
        return results
    finally:
        for changer in changers.values():
            if changer.is_alive():
                changer.stop()
        for drain in drains.values():
            drain.stop()
        for process in processes.values():
            process.stop()
        node.destroy_node()
        rclpy.try_shutdown()


def _spin(node) -> None:
    """Serve the /rosout subscription until the context shuts down."""
    import rclpy
    from rclpy.executors import ExternalShutdownException

    with contextlib.suppress(ExternalShutdownException, rclpy.executors.ShutdownException):
        rclpy.spin(node)


def print_soak(results: dict) -> bool:
    """The soak side by side; True if id_node grew no faster than the relay (second half)."""
    s = results["settings"]
    print(
        f"\nsoak: {s['minutes']:g} min at {s['rate_hz']:g} Hz, {results['sent']} messages to each node, "
        f"payload.mass set every {s['change_period_s']:g} s; RssAnon after a {s['warmup_s']:g} s warm-up\n"
    )
    print(
        f"{'node':<14}{'RssAnon start [MB]':>20}{'RssAnon end [MB]':>18}{'growth [kB]':>13}"
        f"{'kB/min':>9}{'kB/min, 2nd half':>18}{'outputs':>10}{'logs':>7}"
    )

    def fmt(x, spec):
        return "-" if x is None else format(x, spec)

    for kind in KINDS:
        r = results[kind]
        first = r["rss_anon_kb"][0][1] / 1024 if r["rss_anon_kb"] else None
        last = r["rss_anon_kb"][-1][1] / 1024 if r["rss_anon_kb"] else None
        print(
            f"{kind:<14}{fmt(first, '.1f'):>20}{fmt(last, '.1f'):>18}{fmt(r['growth_kb'], '.0f'):>13}"
            f"{fmt(r['slope_kb_per_min'], '.1f'):>9}{fmt(r['slope_second_half_kb_per_min'], '.1f'):>18}"
            f"{r['outputs']:>10}{r.get('log_messages', 0):>7}"
        )
    print(
        "logs: messages each node sent to /rosout; rcl keeps its last 1,000 (~0.5 kB each), so a node that "
        "warns grows by that until it has sent 1,000"
    )
    base = results["relay"]["slope_second_half_kb_per_min"]
    met = {}
    for kind in ("id_node", "id_node_quiet"):
        ours = results[kind]["slope_second_half_kb_per_min"]
        met[kind] = ours is not None and base is not None and ours <= base + TOLERANCE
        print(
            f"target: {kind}'s growth (2nd half) <= the relay's + {TOLERANCE:g} kB/min: "
            f"{'met' if met[kind] else 'MISSED'}"
        )
    return met["id_node"]
