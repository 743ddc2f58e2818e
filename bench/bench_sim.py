"""Benchmark of sim_node: does the simulated arm keep real time at 1 kHz beside id_node?

    .venv/bin/python bench/bench_sim.py [--duration 10] [--rate 1000] [--priority 50]

Prints one table and writes the raw figures to bench/results/sim.json. Two runs, each in
fresh processes with a namespace of their own, as bench_nodes.py starts its nodes:

- baseline: sim_node alone (no controller: one zero-torque command from here, held, so
  that the arm leaves its brakes and MuJoCo steps; the arm rests on its stops);
- ours: sim_node beside id_node closing the loop (effort_commands = g(q), the gravity
  compensation test's setup): two Python processes on the same cores.

Over a window of ``--duration`` seconds after ``--warmup``, bounded by two of sim_node's
/diagnostics messages (their counts are cumulative):

- late steps: steps sim_node ran more than one period after they were due (its own
  count), and skipped steps (the schedule fell more than 50 ms behind and moved on);
- publish lateness: a joint_states message's DDS source timestamp (when sim_node published
  it) - its stamp (when its step was due), p50 / p99 / max over the messages received here;
- sim_node's CPU per step (process user + system time / steps), id_node's CPU share.

Target: late steps < 0.1 % and none skipped, with id_node beside it.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from common import (  # first: the checkout on sys.path
    Row,
    Target,
    Value,
    machine_info,
    print_table,
    shown,
    write_results,
)
from machine_load import OTHERS_WARNING, load_between, snapshot
from node_processes import STARTUP_TIMEOUT, NodeProcess, isolated_domain, wait_for
from receiver import Receiver
from stream_stats import percentiles

POSE = "[0.0, -0.5, 0.5, 0.0, 0.5, 0.0]"  # rad, initial_positions
RATE = 1000.0  # Hz
DURATION = 10.0  # s measured
WARMUP = 2.0  # s after the loop is closed
LATE_TARGET = Target(0.1, absolute=True)  # % of steps
SKIPPED_TARGET = Target(0, absolute=True)
QOS_DEPTH = 1000  # this process's joint_states subscription


def counts_of(msg) -> dict | None:
    for status in msg.status:
        if status.name == "sim_node: simulation":  # the only sim_node of its isolated domain
            return {kv.key: int(kv.value) for kv in status.values if kv.value.isdigit()}
    return None


def run(loop: bool, rate: float, duration: float, warmup: float, env: dict, index: int, priority: int = 0) -> dict:
    """Start sim_node (and id_node when ``loop``), measure a window, return the raw figures."""
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState

    namespace = f"/bench_sim_{os.getpid()}_{index}"
    ros_args = ["--ros-args", "-r", f"__ns:={namespace}"]
    sim = NodeProcess(
        [
            sys.executable,
            "-c",
            "from irb140_dynamics.programs import sim_node; sim_node()",
            *ros_args,
            "-p",
            f"rate:={rate}",
            "-p",
            f"initial_positions:={POSE}",
            "-p",
            f"thread_priority:={priority}",
            *([] if loop else ["-p", "command_timeout:=0.0"]),
        ],
        env,
    )
    controller = None
    if loop:
        controller = NodeProcess(
            [
                sys.executable,
                "-c",
                "from irb140_dynamics.programs import id_node; id_node()",
                *ros_args,
                "-p",
                "effort_commands.enabled:=true",
                "-p",
                "effort_commands.source:=gravity",
            ],
            env,
        )
    listener, taker = Node("bench_sim_listener"), Node("bench_sim_taker")
    executor = SingleThreadedExecutor()
    executor.add_node(listener)
    diagnostics, receiver = [], None
    try:
        listener.create_subscription(
            DiagnosticArray, "/diagnostics", lambda msg: diagnostics.append((time.monotonic(), msg)), 100
        )
        states = taker.create_subscription(
            JointState,
            f"{namespace}/joint_states",
            lambda msg: None,
            QoSProfile(depth=QOS_DEPTH, reliability=ReliabilityPolicy.RELIABLE),
        )
        wait_for(
            lambda: taker.count_publishers(f"{namespace}/joint_states") > 0,
            STARTUP_TIMEOUT,
            sim,
            "sim_node's joint_states",
        )
        if controller is not None:
            wait_for(
                lambda: listener.count_publishers(f"{namespace}/effort_commands") > 0,
                STARTUP_TIMEOUT,
                controller,
                "id_node's effort_commands",
            )
        if controller is None:  # zero torque, held: else the arm stays on its brakes, unstepped
            from std_msgs.msg import Float64MultiArray

            zero = listener.create_publisher(Float64MultiArray, f"{namespace}/effort_commands", 10)
            wait_for(lambda: zero.get_subscription_count() > 0, STARTUP_TIMEOUT, sim, "sim_node's effort_commands")
            for _ in range(10):  # sim_node takes commands best effort
                zero.publish(Float64MultiArray(data=[0.0] * 6))
        receiver = Receiver(states, taker.context)
        receiver.start()

        def spin(seconds: float) -> None:
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                executor.spin_once(timeout_sec=0.05)

        spin(warmup)
        first = len(diagnostics)
        wait_for(
            lambda: spin(0.05) or any(counts_of(m) for _, m in diagnostics[first:]),
            5.0,
            sim,
            "sim_node's /diagnostics",
        )
        start_at, start_msg = next((t, m) for t, m in diagnostics[first:] if counts_of(m))
        cpu0 = sim.cpu_seconds(), controller.cpu_seconds() if controller else 0.0
        load0 = snapshot()
        spin(duration - 0.5)
        later = len(diagnostics)
        wait_for(
            lambda: spin(0.05) or any(counts_of(m) for _, m in diagnostics[later:]),
            5.0,
            sim,
            "sim_node's /diagnostics",
        )
        end_at, end_msg = next((t, m) for t, m in diagnostics[later:] if counts_of(m))
        cpu1 = sim.cpu_seconds(), controller.cpu_seconds() if controller else 0.0
        load1 = snapshot()
        for process in (sim, controller):
            if process is not None and not process.alive():
                raise process.fail("died during the run")
    finally:
        if receiver is not None:
            receiver.stop()
        executor.shutdown(timeout_sec=1.0)
        listener.destroy_node()
        taker.destroy_node()
        for process in (sim, controller):
            if process is not None:
                process.stop()
    c0, c1 = counts_of(start_msg), counts_of(end_msg)
    steps = c1["steps"] - c0["steps"]
    window = (_ns(start_msg.header.stamp), _ns(end_msg.header.stamp))
    records = np.array(receiver.records, dtype=np.int64).reshape(-1, 5)
    inside = records[(records[:, 0] >= window[0]) & (records[:, 0] < window[1])]
    seconds = end_at - start_at
    ours = {os.getpid(), *(p.process.pid for p in (sim, controller) if p is not None)}
    load = load_between(load0, load1, ours)
    return {
        "loop": "beside id_node" if loop else "alone",
        "rate_hz": rate,
        "thread_priority": priority,
        "window_s": seconds,
        "steps": steps,
        "late_steps": c1["late_steps"] - c0["late_steps"],
        "skipped_steps": c1.get("skipped_steps", 0) - c0.get("skipped_steps", 0),
        "late_percent": 100.0 * (c1["late_steps"] - c0["late_steps"]) / max(steps, 1),
        "steps_per_s": steps / seconds,
        "received_here": int(inside.shape[0]),
        "publish_lateness_us": percentiles(inside[:, 1] - inside[:, 0]),
        "sim_cpu_us_per_step": (cpu1[0] - cpu0[0]) / max(steps, 1) * 1e6,
        "sim_cpu_percent": (cpu1[0] - cpu0[0]) / seconds * 100,
        "id_node_cpu_percent": (cpu1[1] - cpu0[1]) / seconds * 100 if loop else None,
        # CPU of everything else on the machine, in cores (not the nodes', not this process's), and steal
        "other_processes_cores": load["other_processes_cores"],
        "stolen_percent": load["stolen_percent"],
    }


def _ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def rows_of(alone: dict, loop: dict) -> list[Row]:
    priority = f", thread_priority {loop['thread_priority']}" if loop["thread_priority"] else ""
    group = (
        f"sim_node at {loop['rate_hz']:g} Hz for {loop['window_s']:.0f} s beside id_node{priority} "
        "(baseline: sim_node alone)"
    )
    rows = [
        Row(
            group,
            f"late steps (of {loop['steps']})",
            Value.of(loop["late_percent"], "%"),
            Value.of(alone["late_percent"], "%"),
            LATE_TARGET,
        ),
        Row(
            group,
            "skipped steps",
            Value.of(loop["skipped_steps"], "msgs"),
            Value.of(alone["skipped_steps"], "msgs"),
            SKIPPED_TARGET,
        ),
        Row(group, "steps per second", Value.of(loop["steps_per_s"], "Hz"), Value.of(alone["steps_per_s"], "Hz")),
    ]
    for stat in ("p50", "p99", "max"):
        rows.append(
            Row(
                group,
                f"publish lateness {stat}",
                Value.of(loop["publish_lateness_us"][stat], "us"),
                Value.of(alone["publish_lateness_us"][stat], "us"),
            )
        )
    rows += [
        Row(
            group,
            "sim_node CPU per step",
            Value.of(loop["sim_cpu_us_per_step"], "us"),
            Value.of(alone["sim_cpu_us_per_step"], "us"),
        ),
        Row(group, "id_node CPU", Value.of(loop["id_node_cpu_percent"], "%")),
    ]
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=DURATION, help="measured seconds per run (default 10)")
    parser.add_argument("--warmup", type=float, default=WARMUP, help="seconds before measuring (default 2)")
    parser.add_argument("--rate", type=float, default=RATE, help="sim_node's rate, Hz (default 1000)")
    parser.add_argument(
        "--priority",
        type=int,
        default=0,
        help="sim_node's thread_priority (SCHED_FIFO 1..99; default 0: ordinary scheduling)",
    )
    parser.add_argument("--domain-id", type=int, default=None, help="ROS_DOMAIN_ID (default: random in 50..99)")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    domain_id, env = isolated_domain(args.domain_id)

    import rclpy

    rclpy.init()
    runs = []
    try:
        for index, loop in enumerate((False, True)):
            print(
                f"  sim_node {'beside id_node' if loop else 'alone'} at {args.rate:g} Hz: "
                f"{args.warmup + args.duration:g} s ...",
                flush=True,
            )
            runs.append(run(loop, args.rate, args.duration, args.warmup, env, index, args.priority))
            r = runs[-1]
            print(
                f"    {r['late_steps']} of {r['steps']} steps late ({r['late_percent']:.3f} %), "
                f"{r['skipped_steps']} skipped, CPU {r['sim_cpu_us_per_step']:.0f} us/step",
                flush=True,
            )
    finally:
        rclpy.try_shutdown()
    rows = rows_of(*runs)
    print_table(rows, "sim_node real time (ratio = beside id_node / alone)")
    worst = max(r["other_processes_cores"] for r in runs)
    if worst > OTHERS_WARNING:
        print(
            f"note: other processes used up to {worst:.2f} of {os.cpu_count()} cores during the runs: "
            "late steps are not those of an idle machine"
        )
    path = write_results(
        "sim",
        {
            "benchmark": "sim",
            "machine": machine_info(("numpy", "rclpy", "mujoco")),
            "settings": {
                "duration_s": args.duration,
                "warmup_s": args.warmup,
                "rate_hz": args.rate,
                "thread_priority": args.priority,
                "ros_domain_id": domain_id,
                "rmw": os.environ.get("RMW_IMPLEMENTATION", "default (rmw_fastrtps_cpp)"),
            },
            "rows": [row.as_dict() for row in rows],
            "runs": runs,
            "runtime_s": time.perf_counter() - started,
        },
    )
    print(f"raw figures: {shown(path)} ({time.perf_counter() - started:.0f} s)")


if __name__ == "__main__":
    main()
