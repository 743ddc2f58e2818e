"""Benchmark: what id_node's ~/markers cost the joint-state stream, markers on against off.

    .venv/bin/python bench/bench_markers.py [--duration 10] [--rate 1000] [--repeat 3]

id_node runs in its own process (as ``ros2 run`` starts it) with joint states carrying
efforts (the momentum observer on, external torques for the markers' arrow) streamed at
``--rate`` from this process (bench/stream.py), once with ``markers.rate`` at its default,
10 Hz, and once at 0 (off, the baseline), alternating, each ``--repeat`` times in a fresh
process; this process subscribes to ``~/markers`` in both, as RViz would (with nobody
subscribed, id_node builds no markers). Rows: the delay publish -> feedforward_torques received (p50, p99, max, medians
over the runs), the messages lost (total) and the node's CPU per message. Raw figures:
bench/results/markers.json.
"""

from __future__ import annotations

import argparse
import time
from statistics import median

from common import (  # first: puts the checkout on sys.path
    Row,
    Target,
    Value,
    machine_info,
    print_table,
    shown,
    write_results,
)
from node_processes import MARKERS_OFF, isolated_domain
from stream import stream_run
from stream_table import LOST_TARGET
from visualization_msgs.msg import MarkerArray

KINDS = (MARKERS_OFF, "id_node")  # the baseline first, then the default (markers at 10 Hz)
P99_TARGET = Target(1.5)  # p99 delay with markers at most 1.5x without
VIEWER = (MarkerArray, "id_node/markers")  # subscribed in both, as RViz would: id_node builds none for nobody


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=10.0, help="measured seconds per run (default 10)")
    parser.add_argument("--warmup", type=float, default=1.0, help="seconds streamed before measuring (default 1)")
    parser.add_argument("--rate", type=float, default=1000.0, help="joint states per second (default 1000)")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each, alternating (default 3)")
    parser.add_argument("--domain-id", type=int, default=None, help="ROS_DOMAIN_ID (default: random in 50..99)")
    return parser.parse_args(argv)


def rows_of(runs: list[dict], rate: float, duration: float) -> list[Row]:
    on, off = ([r for r in runs if r["node"] == kind] for kind in ("id_node", MARKERS_OFF))
    group = f"id_node at {rate:g} Hz with efforts, markers at 10 Hz (baseline: markers off), {len(on)} runs each"
    rows = []
    for stat, target in (("p50", None), ("p99", P99_TARGET), ("max", None)):
        ours, base = (Value.of(median([r["delay_us"][stat] for r in side]), "us") for side in (on, off))
        rows.append(Row(group, f"delay {stat}", ours, base, target))
    sent = sum(r["sent"] for r in on)
    lost = [Value.of(sum(r["lost"] for r in side), "msgs") for side in (on, off)]
    rows.append(Row(group, f"lost (of {sent} sent)", *lost, LOST_TARGET))
    cpu = [Value.of(median([r["node_cpu_us_per_msg"] for r in side]), "us/msg") for side in (on, off)]
    rows.append(Row(group, "node CPU per message", *cpu))
    return rows


def main(argv=None) -> None:
    import rclpy
    from rclpy.node import Node

    args = parse_args(argv)
    started = time.perf_counter()
    domain_id, env = isolated_domain(args.domain_id)
    rclpy.init()
    node = Node("bench_markers_load")
    runs = []
    try:
        for kind in KINDS * args.repeat:
            print(f"  {kind} at {args.rate:g} Hz: {args.warmup + args.duration:g} s ...", flush=True)
            run = stream_run(
                node, kind, "events", args.rate, args.duration, args.warmup, env, len(runs), effort=True, listen=VIEWER
            )
            runs.append(run)
            d = run["delay_us"]
            print(f"    p50 {d['p50']:.0f} us, p99 {d['p99']:.0f} us, lost {run['lost']} of {run['sent']}", flush=True)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    rows = rows_of(runs, args.rate, args.duration)
    print_table(rows, "id_node's markers (ratio = markers on / off; delays: publish -> torques received)")
    path = write_results(
        "markers",
        {
            "benchmark": "markers",
            "machine": machine_info(("numpy", "rclpy")),
            "settings": {"duration_s": args.duration, "rate_hz": args.rate, "repeat": args.repeat, "domain": domain_id},
            "rows": [row.as_dict() for row in rows],
            "runs": runs,
            "runtime_s": time.perf_counter() - started,
        },
    )
    print(f"raw figures: {shown(path)} ({time.perf_counter() - started:.0f} s)")


if __name__ == "__main__":
    main()
