"""The longer run of the nodes' parameter fuzz (test/ros/test_fuzz_parameter_ranges.py runs
60 values per node): every node in-process, CASES values per node drawn from
test.support.fuzz_ranges (inf, nan, 1e308, negatives, integers, values in and around each
numeric parameter's range), each set as `ros2 param set` would. Prints, per node and kind
of value, how many were tried, accepted and refused, and every case answered wrongly
(accepted out of range, refused without a reason, a value changed by a refusal, ...).

    .venv/bin/python bench/fuzz_parameters.py [--cases 2000] [--seed 23]

Exit 1 when any case was answered wrongly. See docs/robustness.md ("Nodes").
"""

from __future__ import annotations

import argparse
import math
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import rclpy
from rclpy.context import Context

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from test.support.fuzz_ranges import NODES, SEED, answer, bounds, candidates, numeric_parameters  # noqa: E402


def kind_of(value, descriptor) -> str:
    """The kind of a value, for the table."""
    if isinstance(value, float) and not math.isfinite(value):
        return "inf/nan"
    low, high = bounds(descriptor)
    if abs(value) >= 1e300:
        return "1e308"
    if isinstance(value, int) and descriptor.type == 3:
        return "int for a double" if low <= value <= high else "int, out of range"
    if low <= value <= high:
        return "in range"
    return "negative, out of range" if value < 0 else "out of range"


def fuzz(name: str, cases: int, seed: int) -> tuple[Counter, list[str]]:
    context = Context()
    rclpy.init(context=context)
    counts, problems = Counter(), []
    try:
        node = NODES[name](context=context)
        numeric = numeric_parameters(node)
        names = sorted(numeric)
        rng = np.random.default_rng(seed)
        for _ in range(cases):
            parameter = names[rng.integers(len(names))]
            values = candidates(rng, numeric[parameter])
            value = values[rng.integers(len(values))]
            accepted, problem = answer(node, parameter, numeric[parameter], value)
            kind = kind_of(value, numeric[parameter])
            counts[(kind, "tried")] += 1
            counts[(kind, "accepted" if accepted else "refused")] += 1
            if problem is not None:
                problems.append(problem)
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    return counts, problems


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=2000, help="values per node (default 2000)")
    parser.add_argument("--seed", type=int, default=SEED)
    options = parser.parse_args()
    failed = 0
    print(f"{'node':20} {'kind of value':24} {'tried':>6} {'accepted':>9} {'refused':>8}")
    for name in sorted(NODES):
        counts, problems = fuzz(name, options.cases, options.seed)
        for kind in sorted({k for k, _ in counts}):
            print(
                f"{name:20} {kind:24} {counts[(kind, 'tried')]:6} {counts[(kind, 'accepted')]:9} "
                f"{counts[(kind, 'refused')]:8}"
            )
        for problem in problems[:20]:
            print(f"  WRONG: {problem}")
        failed += len(problems)
    print(f"{'wrong answers':45} {failed}")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
