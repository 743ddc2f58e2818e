"""The longer fuzz of ``load_urdf``: many more mutated URDFs than the test's, seeded.

    .venv/bin/python bench/fuzz_urdf.py [--cases 20000] [--seed 23]

Each case is the test's seed URDF (test/support/urdf_mutations.py) after 1 to 6 random edits,
loaded with and without base/tip links. Prints how many were loaded, refused (one line
under 300 characters) and defects (anything else), and the defects themselves; exit 1 if
there is one. See docs/robustness.md.
"""

from __future__ import annotations

import argparse
import collections
import sys
import time

import common  # noqa: F401  (first: puts the checkout on sys.path)
import numpy as np

from test.support.urdf_mutations import KINDS, SEED_TEXT, mutated, outcome  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=20_000)
    parser.add_argument("--seed", type=int, default=23)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    started = time.perf_counter()
    counts: collections.Counter[str] = collections.Counter()
    defects = []
    for case in range(args.cases):
        edits = [
            (KINDS[rng.integers(len(KINDS))], float(rng.random()) * 0.999, int(rng.integers(1000)))
            for _ in range(rng.integers(1, 7))
        ]
        ends = {"base_link": "base", "tip_link": "tool0"} if case % 2 else {}
        result = outcome(mutated(SEED_TEXT, edits), ends)
        counts[result.split(":")[0]] += 1
        if result.startswith("defect"):
            defects.append(f"case {case}: {result} (edits {edits}, ends {ends})")
    seconds = time.perf_counter() - started
    print(
        f"load_urdf fuzz: {args.cases} cases (seed {args.seed}) in {seconds:.0f} s: "
        + ", ".join(f"{counts[k]} {k}" for k in ("loaded", "refused", "defect"))
    )
    for line in defects[:50]:
        print(line)
    return 1 if defects else 0


if __name__ == "__main__":
    sys.exit(main())
