"""Benchmark of the IRB-140's load diagram at 1 cm steps over 0.3 m x 0.2 m (651 points).

    .venv/bin/python bench/bench_load_diagram.py [--samples 12] [--workers 2]

- ours: ``load_diagram`` (the tool's core) over the whole grid, its rows shared by
  ``--workers`` forked processes: wall time, and CPU time of all processes (what it would
  take on idle cores: the machine is shared);
- baseline, in the same run: what the payload check would take for the same diagram, one
  payload at a time: ``workspace_load`` (the largest payload of a shape, proven, as
  ``~/check`` computes it) on the arm with the CoM's direction as a joint, for ``--samples``
  points of the grid, scaled to its 651 points.

Target: ours under 60 s on 2 cores (the CPU time over 2 is the idle-machine figure). Then
two 7-joint arms with their URDF's efforts over the same area: the Panda at 5 cm steps (35
points) and, where example-robot-data is installed, the xArm7 at 10 cm (12 points): their
times and the share of points proven (the issue's floor: 90 %). Prints one table, writes
bench/results/load_diagram.json.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import os
import resource
import time

import numpy as np
from common import REPO, Row, Target, Value, example_robot_urdf, machine_info, print_table, write_results

from irb140_dynamics.core import RigidBody, derive_torque_limits, irb140
from irb140_dynamics.core.payload import workspace_load
from irb140_dynamics.core.payload.diagram import load_diagram, pivoted
from irb140_dynamics.core.urdf import load_urdf

Z, L = np.arange(31) * 0.01, np.arange(21) * 0.01


def cpu_seconds() -> float:
    """CPU time of this process and its finished children (the forked workers)."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


SEVEN: dict = {}  # per 7-joint arm: wall_s, cpu_s, masses_kg
PROVEN = Target(90.0, at_least=True, absolute=True)


def xarm7():
    """example-robot-data's xArm7 to its ``link_eef`` (None: the package is not installed)."""
    try:
        path = example_robot_urdf("xarm_description/urdf/xarm7.urdf")
    except importlib.metadata.PackageNotFoundError:
        return None
    return load_urdf(path.read_text(), tip_link="link_eef").model


def seven_joints(name: str, model, every: int, workers: int) -> list:
    """A 7-joint arm's diagram over the same area at ``every`` cm, its URDF's efforts: rows."""
    z, l = Z[::every], L[::every]
    cpu, started = cpu_seconds(), time.perf_counter()
    diagram = load_diagram(model, model.torque_limits, z, l, workers=workers)
    wall, cpu = time.perf_counter() - started, cpu_seconds() - cpu
    SEVEN[name] = {"wall_s": wall, "cpu_s": cpu, "masses_kg": diagram.masses().tolist()}
    group = f"{name} (7 joints), {z.size} x {l.size} = {z.size * l.size} points at {every} cm, {workers} workers"
    return [
        Row(group, "diagram, wall", Value.of(wall, "s")),
        Row(group, "diagram, CPU / 2 cores (an idle machine)", Value.of(cpu / 2, "s")),
        Row(group, "proven points", Value.of(100 * diagram.proven_share, "%"), target=PROVEN),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=12, help="grid points the baseline is timed on (default 12)")
    parser.add_argument("--workers", type=int, default=2, help="processes of ours (default 2)")
    args = parser.parse_args()
    model = irb140()
    limits = derive_torque_limits(model).values
    load_before = os.getloadavg()[0]

    cpu, started = cpu_seconds(), time.perf_counter()
    diagram = load_diagram(model, limits, Z, L, workers=args.workers)
    wall, cpu = time.perf_counter() - started, cpu_seconds() - cpu

    arm = pivoted(model)
    rng = np.random.default_rng(0)
    points = [(Z[rng.integers(Z.size)], L[rng.integers(L.size)]) for _ in range(args.samples)]
    workspace_load(arm, RigidBody(1.0, (0.01, 0.0, 0.01)), np.append(limits, np.inf))  # compiled, as ours was
    started = time.perf_counter()
    for z, l in points:
        workspace_load(arm, RigidBody(1.0, (l, 0.0, z)), np.append(limits, np.inf))
    per_point = (time.perf_counter() - started) / args.samples
    baseline = per_point * Z.size * L.size

    group = f"IRB-140, {Z.size} x {L.size} = {Z.size * L.size} points, {args.workers} workers"
    rows = [
        Row(group, "diagram, wall", Value.of(wall, "s"), Value.of(baseline, "s"), Target(60.0, absolute=True)),
        Row(
            group,
            "diagram, CPU / 2 cores (an idle machine)",
            Value.of(cpu / 2, "s"),
            target=Target(60.0, absolute=True),
        ),
        Row(group, "proven points", Value.of(100 * diagram.proven_share, "%"), target=PROVEN),
    ]
    panda = load_urdf((REPO / "test/data/urdf/panda.urdf").read_text(), tip_link="panda_hand_tcp").model
    rows += seven_joints("Panda", panda, 5, args.workers)
    arm7 = xarm7()
    rows += [] if arm7 is None else seven_joints("xArm7", arm7, 10, args.workers)
    load_after = os.getloadavg()[0]
    print_table(rows, "load diagram (baseline: the payload check's workspace_load per point, scaled)")
    print(f"load average {load_before:.1f} before, {load_after:.1f} after")
    path = write_results(
        "load_diagram",
        {
            "benchmark": "load_diagram",
            "machine": machine_info(("numpy",)),
            "settings": {"samples": args.samples, "workers": args.workers, "points": int(Z.size * L.size)},
            "rows": [row.as_dict() for row in rows],
            "wall_s": wall,
            "cpu_s": cpu,
            "baseline_per_point_s": per_point,
            "load_average": [load_before, load_after],
            "masses_kg": diagram.masses().tolist(),
            "seven_joints": SEVEN,
        },
    )
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
