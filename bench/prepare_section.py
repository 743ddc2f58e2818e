"""bench_core's section on ``prepare``: how long a fresh process takes to make a model's
native kernels ready, with an empty kernel cache and with a filled one."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

from common import REPO, Figure, Row  # first: puts the checkout on sys.path

PREPARE = """
import sys
import numpy as np
from irb140_dynamics.core import irb140, prepare
from irb140_dynamics.core.io.urdf import load_urdf
from test.support.common import random_model
if sys.argv[1] == "-":
    model = irb140()
elif sys.argv[1] == "chain":
    model = random_model(np.random.default_rng(30), int(sys.argv[2]))
else:
    model = load_urdf(open(sys.argv[1]).read(), tip_link=sys.argv[2]).model
done = prepare(model)
print(done.seconds if done.native else "nan")
"""
CHAIN = 30  # joints of the long chain timed too: the documented bound


def preparation(urdf_paths: dict) -> list[Row]:
    """``prepare(model)`` in a fresh process: with an empty kernel cache (traces and
    compiles the three native kernels, the compiler at the lowest priority), then again
    with that cache (traces, loads and checks them): what a node waits for at startup."""
    rows = []
    arms = {"IRB-140": ("-", "-"), **{name: (str(path), tip) for name, (path, tip) in urdf_paths.items()}}
    arms[f"a random {CHAIN}-joint chain"] = ("chain", str(CHAIN))
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "IRB140_CACHE": cache}
        for name, args in arms.items():
            for state in ("empty cache", "cached"):
                done = subprocess.run(
                    [sys.executable, "-c", PREPARE, *args],
                    cwd=REPO,
                    env=env,
                    capture_output=True,
                    text=True,
                    check=True,
                )
                seconds = float(done.stdout.split()[-1])
                rows.append(
                    Row(
                        "prepare(model): native kernels in a fresh process",
                        f"{name}, {state}",
                        Figure.cost([seconds], "ms"),
                    )
                )
    return rows
