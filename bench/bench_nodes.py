"""Benchmark of the nodes over real DDS: id_node end to end against a relay, and the payload check.

    .venv/bin/python bench/bench_nodes.py [--duration 10] [--rates 1000 2000]
        [--executor events [single_threaded]] [--no-event-handlers] [--profile] [--no-payload] [--no-stream]
        [--change-period 0.1] [--no-changes]
    .venv/bin/python bench/bench_nodes.py --soak MINUTES

Prints one table and writes the raw figures to bench/results/nodes.json. Sections:

- end to end, per rate and executor (bench/stream.py): the node under test runs in its
  own process (id_node as its console script runs it, or the baseline
  bench/relay_node.py, which republishes joint_states unchanged on feedforward_torques
  with the same QoS). This process publishes JointState at a fixed rate for a warm-up and
  then ``--duration`` seconds, and takes the torque messages as they arrive: their delay,
  the messages lost, the node's CPU per message.
- parameter changes: the relay and id_node again at 1 kHz while payload.mass is set every
  ``--change-period`` s through the SetParameters service (bench/parameter_changes.py).
- soak (``--soak MINUTES``, alone): id_node and the relay side by side under the same load,
  their RSS growth (bench/soak.py, bench/results/soak.json).
- payload check (bench/payload_section.py): check_payload() cold (first call in a fresh process, kernel compilation
  included; the rated payload, and an off-axis one whose proof spends its budget) and warm,
  its two halves (derive_torque_limits, workspace_load) alone, and the round trip of a
  ``~/check`` service call on a running payload_check_node.

The script sets ROS_DOMAIN_ID (random in 50..99 unless --domain-id) and
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST for itself and the nodes it starts, and gives every
node its own namespace; nodes are stopped on exit whatever happens.
"""

from __future__ import annotations

import argparse
import os
import time

from common import machine_info, print_table, shown, write_results  # first: puts the checkout on sys.path
from machine_load import OTHERS_WARNING, STOLEN_WARNING
from node_processes import QOS_DEPTH, isolated_domain
from payload_section import payload_rows
from soak import print_soak, soak
from stream import CHANGE_RATE, RECEIVER_DEPTH, end_to_end

from irb140_dynamics.ros.runtime.spin import EXECUTORS  # noqa: E402  (events: what every node's main() uses)

RATES = (1000, 2000)  # Hz
CHANGE_PERIOD = 0.1  # s between two parameter changes in the run at CHANGE_RATE
DURATION = 10.0  # s measured, per run
WARMUP = 1.0  # s streamed before the measured window
REPEAT = 3  # runs of each pair (relay, id_node): one run's p99 moves 2-3x with this VM's stalls


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=DURATION, help="measured seconds per run (default 10)")
    parser.add_argument("--warmup", type=float, default=WARMUP, help="seconds streamed before measuring (default 1)")
    parser.add_argument("--rates", type=float, nargs="+", default=list(RATES), help="Hz (default 1000 2000)")
    parser.add_argument(
        "--executor",
        nargs="+",
        choices=EXECUTORS,
        default=["events"],
        help="executor of both nodes: events (rclpy.experimental.EventsExecutor, as "
        "main() does; default) and/or single_threaded (rclpy.spin)",
    )
    parser.add_argument(
        "--no-event-handlers",
        action="store_true",
        help="run both nodes without rclpy's default QoS event handlers (a bench-only variant through relay_node.py)",
    )
    parser.add_argument("--no-payload", action="store_true", help="skip the payload check section")
    parser.add_argument(
        "--change-period",
        type=float,
        default=CHANGE_PERIOD,
        help=f"s between two payload.mass changes in the run at {CHANGE_RATE} Hz with parameter "
        f"changes (default {CHANGE_PERIOD:g})",
    )
    parser.add_argument("--no-changes", action="store_true", help="skip the run with parameter changes")
    parser.add_argument(
        "--repeat",
        type=int,
        default=REPEAT,
        help=f"runs of each pair, relay and id_node in turn; the table shows medians and total "
        f"losses (default {REPEAT})",
    )
    parser.add_argument(
        "--soak",
        type=float,
        metavar="MINUTES",
        default=None,
        help="only the soak: id_node and the relay side by side at 1 kHz for MINUTES "
        "(10 in the issue), their RSS growth (bench/results/soak.json)",
    )
    parser.add_argument("--no-stream", action="store_true", help="skip the end-to-end section")
    parser.add_argument(
        "--depth",
        type=int,
        default=QOS_DEPTH,
        help=f"qos.depth of both nodes (default {QOS_DEPTH}, id_node's): their joint_states queue "
        "holds depth / rate seconds of a stall",
    )
    parser.add_argument(
        "--effort",
        action="store_true",
        help="joint states carry efforts: id_node's momentum observer runs on every message",
    )
    parser.add_argument(
        "--profile",
        action="store_true",
        help="sample each node with py-spy over the measured window "
        "(bench/results/profile_*.txt; perturbs the figures a little)",
    )
    parser.add_argument("--domain-id", type=int, default=None, help="ROS_DOMAIN_ID (default: random in 50..99)")
    return parser.parse_args(argv)


def main(argv=None) -> None:
    args = parse_args(argv)
    started = time.perf_counter()
    domain_id, env = isolated_domain(args.domain_id)
    if args.soak is not None:
        results = soak(args.soak, CHANGE_RATE, env)
        print_soak(results)
        path = write_results(
            "soak",
            {
                "benchmark": "soak",
                "machine": machine_info(("numpy", "rclpy")),
                **results,
                "runtime_s": time.perf_counter() - started,
            },
        )
        print(f"raw figures: {shown(path)}")
        return

    rows, runs, payload = [], [], {}
    if not args.no_stream:
        stream, runs = end_to_end(
            args.rates,
            args.executor,
            args.duration,
            args.warmup,
            env,
            args.profile,
            args.no_event_handlers,
            None if args.no_changes else args.change_period,
            effort=args.effort,
            repeat=args.repeat,
            depth=args.depth,
        )
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
        print(
            f"note: other processes used up to {worst:.2f} of {os.cpu_count()} cores during "
            f"{len(busy)} of {len(runs)} runs: the delays and losses are not those of an idle machine"
        )
    stolen = [r for r in runs if r["stolen_percent"] > STOLEN_WARNING]
    if stolen:
        print(
            f"note: the hypervisor took up to {max(r['stolen_percent'] for r in stolen):.1f} % of the CPUs' time "
            f"(steal) during {len(stolen)} of {len(runs)} runs: stalls of a shared host, not of these processes"
        )
    if args.profile:
        print("profiled (py-spy): figures perturbed; share of the node's samples, inclusive:")
        for r in runs:
            top = ", ".join(f"{name} {share:g}%" for name, share in r.get("profile", {}).get("top", [])[:8])
            print(f"  {r['node']} {r['rate_hz']:g} Hz {r['executor']}: {top}")
    name = ("nodes_effort" if args.effort else "nodes") + ("" if args.depth == QOS_DEPTH else f"_depth{args.depth}")
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
                "qos": {
                    "joint_states": f"best_effort, depth {args.depth}",
                    "feedforward_torques": f"reliable, depth {args.depth} (node) / {RECEIVER_DEPTH} (here)",
                },
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
    print(f"raw figures: {shown(path)} ({time.perf_counter() - started:.0f} s)")


if __name__ == "__main__":
    main()
