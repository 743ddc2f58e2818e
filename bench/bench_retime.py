"""Benchmark of trajectory re-timing and checking against toppra, in the same run.

    .venv/bin/python bench/bench_retime.py [--blocks 5]

The path: a 6-joint, 100-waypoint trajectory of the IRB-140 as a planner sends it
(positions, velocities, accelerations; rest at both ends; test/support/trajectories.py),
with 0 and 6 kg at the flange. Both re-time the same path on the same grid (about 1000
steps) under the same limits (the params' velocity and acceleration limits, the derived
torque limits):

- ours: ``retime`` whole (the two called in turn, best of ``--blocks`` calls each): the path grid, the profile, the output, the verification played
  as the controller plays it, 10 samples per step, and its rounds;
- baseline: toppra (TOPPRA, seidel solver, collocation) on our path grid, with our rnea as
  its inverse dynamics: the constraints' evaluation and the parameterization.

Rows: the cost of re-timing (target: ours no slower, <= 1x); the durations of the re-timed
trajectories, ours against toppra's at 0 violations (toppra's limits lowered until its
playback keeps them: target <= 1.01x) and toppra's own (which overshoots between grid
points); the check of the 100-point trajectory (target: within the node's 1 s).
Prints one table, writes bench/results/retime.json.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from common import Figure, Row, Target, Value, machine_info, print_table, seconds_per_call, write_results

from irb140_dynamics.core import RigidBody, irb140
from irb140_dynamics.core.trajectories import check_trajectory, retime, trajectory_limits
from test.support.toppra_baseline import toppra_within_limits, toppra_x
from test.support.trajectories import smooth_trajectory

Q0 = np.array([0.0, -0.3, 0.5, 0.0, 0.3, 0.0])
AMPLITUDE = np.array([1.5, 0.6, 0.7, 2.0, 1.2, 2.5])
POINTS, DURATION = 100, 10.0


def alternating(ours, baseline, blocks: int) -> tuple[list[float], list[float]]:
    """Seconds per call of each, called in turn (a load that comes and goes hits both alike)."""
    ours(), baseline()
    times = ([], [])
    for _ in range(blocks):
        for fn, out in zip((ours, baseline), times):
            started = time.perf_counter()
            fn()
            out.append(time.perf_counter() - started)
    return times


def rows_for(payload: float, blocks: int) -> tuple[list[Row], dict]:
    model = irb140().with_payload(RigidBody(payload))
    tr = smooth_trajectory(model.joint_names, Q0, AMPLITUDE, points=POINTS, duration=DURATION)
    limits = trajectory_limits(model)
    ours = retime(model, tr, limits)
    grid = ours.grid
    cost_ours, cost_toppra = alternating(
        lambda: retime(model, tr, limits), lambda: toppra_x(model, grid, limits), blocks
    )
    within, raw, raw_worst, factor = toppra_within_limits(model, grid, tr, limits)
    check_cost = seconds_per_call(lambda: check_trajectory(model, tr, limits), blocks=blocks, number=1)
    group = f"{payload:g} kg, {POINTS} waypoints, {len(grid.s) - 1} grid steps"
    rows = [
        Row(group, "re-time", Figure.cost(cost_ours, "ms"), Figure.cost(cost_toppra, "ms"), Target(1.0)),
        Row(
            group,
            "duration vs toppra at 0 violations",
            Value.of(ours.duration, "s"),
            Value.of(within, "s"),
            Target(1.01),
        ),
        Row(group, "duration vs toppra's own", Value.of(ours.duration, "s"), Value.of(raw, "s")),
        Row(group, "check, 100 points", Figure.cost(check_cost, "ms"), target=Target(1000.0, absolute=True)),
    ]
    details = {
        "payload_kg": payload,
        "grid_steps": len(grid.s) - 1,
        "output_points": len(ours.trajectory.t),
        "ours_duration_s": ours.duration,
        "ours_rounds": ours.rounds,
        "ours_worst_use": ours.worst,
        "toppra_duration_s": raw,
        "toppra_worst_use": raw_worst,
        "toppra_duration_within_limits_s": within,
        "toppra_limit_factor": factor,
    }
    return rows, details


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--blocks", type=int, default=15, help="timed calls of each (default 15)")
    args = parser.parse_args()
    started = time.perf_counter()
    rows, runs = [], []
    for payload in (0.0, 6.0):
        r, details = rows_for(payload, args.blocks)
        rows += r
        runs.append(details)
    print_table(rows, "trajectory re-timing (ratio = ours / toppra)")
    path = write_results(
        "retime",
        {
            "benchmark": "retime",
            "machine": machine_info(("numpy", "scipy", "toppra")),
            "settings": {"points": POINTS, "blocks": args.blocks},
            "rows": [row.as_dict() for row in rows],
            "runs": runs,
            "runtime_s": time.perf_counter() - started,
        },
    )
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
