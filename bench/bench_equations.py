"""Benchmark of the generated equations (the `equations` tool) on the IRB-140.

    .venv/bin/python bench/bench_equations.py

Prints one table and writes bench/results/equations.json. Rows:

- C tau, timed in a C loop (a driver compiled here with the generated file, -O2) and
  through ctypes from Python, against pin.rnea called from Python (Pinocchio's C++ RNEA
  with the call's overhead: no C++ loop of Pinocchio is at hand, so this is the baseline
  the issue names). Target: no slower.
- the generated Python batch tau(Q, QD, QDD) against the package's rnea_batch, states per
  second on the same states. Target: no slower.
- generation time (derivation, common subexpressions, the C form) for the IRB-140
  (6 joints, target 60 s) and the Panda (7 joints, target 180 s), wall and CPU time.

Every pair is checked to give the same numbers before it is timed.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
from common import (
    # first: puts the checkout on sys.path
    REPO,
    Figure,
    Row,
    Target,
    Value,
    machine_info,
    print_table,
    seconds_per_call,
    shown,
    write_results,
)

from irb140_dynamics.core import irb140, rnea, rnea_batch
from irb140_dynamics.core.equations import generate
from irb140_dynamics.core.io.urdf import load_urdf
from test.support.pinocchio_model import build as pinocchio_model

CC = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-O2"]
BATCH_STATES = 100_000
LOOP_STATES = 1024  # the C loop cycles through these (no constant folding of one state)
LOOP_CALLS = 2_000_000
SEED = 140

DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "irb140_eom.h"

int main(int argc, char **argv)
{
    if (argc != 3) return 2;
    long calls = atol(argv[1]);
    int blocks = atoi(argv[2]);
    static double q[STATES][6], qd[STATES][6], qdd[STATES][6];
    double tau[6], sum = 0.0;
    unsigned s = 12345u;
    for (int i = 0; i < STATES; ++i)
        for (int j = 0; j < 6; ++j) {
            s = s * 1103515245u + 12345u; q[i][j] = (double)(s >> 8) / 16777216.0 * 6.0 - 3.0;
            s = s * 1103515245u + 12345u; qd[i][j] = (double)(s >> 8) / 16777216.0 * 4.0 - 2.0;
            s = s * 1103515245u + 12345u; qdd[i][j] = (double)(s >> 8) / 16777216.0 * 10.0 - 5.0;
        }
    for (int b = 0; b < blocks; ++b) {
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        for (long k = 0; k < calls; ++k) {
            int i = (int)(k % STATES);
            irb140_tau(q[i], qd[i], qdd[i], tau);
            sum += tau[k % 6];
        }
        clock_gettime(CLOCK_MONOTONIC, &t1);
        printf("%.12e\n", ((t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec)) / calls);
    }
    fprintf(stderr, "%g\n", sum);
    return 0;
}
"""


def check_same(label: str, ours, theirs) -> None:
    if not np.allclose(ours, theirs, rtol=1e-9, atol=1e-9 * np.abs(theirs).max()):
        raise SystemExit(f"{label}: not the same numbers")


def c_rows(model, folder: Path) -> list[Row]:
    compiler = shutil.which("cc") or shutil.which("gcc")
    pm = pinocchio_model(model)
    data = pm.createData()
    rng = np.random.default_rng(SEED)
    q, qd, qdd = rng.uniform(-3, 3, 6), rng.normal(0, 2, 6), rng.normal(0, 5, 6)
    baseline = Figure.cost(seconds_per_call(lambda: pin.rnea(pm, data, q, qd, qdd)))
    if compiler is None:
        return [Row("C tau (IRB-140)", "C tau", Figure(0, 0, "us"), None, None)]
    library = folder / "libirb140.so"
    subprocess.run(
        [compiler, *CC, "-shared", "-fPIC", str(folder / "irb140_eom.c"), "-o", str(library), "-lm"], check=True
    )
    fn = ctypes.CDLL(str(library)).irb140_tau
    fn.restype = None
    pointer = ctypes.POINTER(ctypes.c_double)
    out = np.empty(6)
    args = [np.ascontiguousarray(a).ctypes.data_as(pointer) for a in (q, qd, qdd, out)]
    fn(*args)
    check_same("C tau vs rnea", out, rnea(model, q, qd, qdd))
    check_same("pin.rnea vs rnea", pin.rnea(pm, data, q, qd, qdd), rnea(model, q, qd, qdd))
    through_ctypes = Figure.cost(seconds_per_call(lambda: fn(*args)))

    (folder / "driver.c").write_text(DRIVER)
    driver = folder / "driver"
    subprocess.run(
        [
            compiler,
            *CC,
            f"-DSTATES={LOOP_STATES}",
            "-I",
            str(folder),
            str(folder / "driver.c"),
            str(folder / "irb140_eom.c"),
            "-o",
            str(driver),
            "-lm",
        ],
        check=True,
    )
    lines = subprocess.run(
        [str(driver), str(LOOP_CALLS // 10), "15"], check=True, capture_output=True, text=True
    ).stdout.split()
    in_c = Figure.cost([float(x) for x in lines], "us")
    return [
        Row("C tau (IRB-140)", "C tau in a C loop vs pin.rnea from Python", in_c, baseline, Target(1.0)),
        Row("C tau (IRB-140)", "C tau through ctypes vs pin.rnea from Python", through_ctypes, baseline, Target(1.0)),
    ]


def python_rows(model, folder: Path) -> list[Row]:
    import importlib.util

    spec = importlib.util.spec_from_file_location("irb140_eom", folder / "irb140_eom.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    rng = np.random.default_rng(SEED)
    Q, QD, QDD = (
        rng.uniform(-3, 3, (BATCH_STATES, 6)),
        rng.normal(0, 2, (BATCH_STATES, 6)),
        rng.normal(0, 5, (BATCH_STATES, 6)),
    )
    check_same(
        "Python batch tau vs rnea_batch",
        module.tau(Q[:1000], QD[:1000], QDD[:1000]),
        rnea_batch(model, Q[:1000], QD[:1000], QDD[:1000]),
    )
    ours = seconds_per_call(lambda: module.tau(Q, QD, QDD), blocks=7, number=1)
    theirs = seconds_per_call(lambda: rnea_batch(model, Q, QD, QDD), blocks=7, number=1)
    return [
        Row(
            "Python batch (IRB-140, 100k states)",
            "generated tau(Q, QD, QDD) vs rnea_batch",
            Figure.rate(ours, BATCH_STATES),
            Figure.rate(theirs, BATCH_STATES),
            Target(1.0, at_least=True),
        )
    ]


def generation_rows() -> tuple[list[Row], dict]:
    rows, files = [], {}
    arms = {
        "IRB-140 (6 joints)": (irb140(), 60.0),
        "Panda (7 joints)": (
            load_urdf((REPO / "test/data/urdf/panda.urdf").read_text(), tip_link="panda_link8").model,
            180.0,
        ),
    }
    for name, (model, limit) in arms.items():
        wall, cpu = time.perf_counter(), time.process_time()
        generated = generate(model, ("c", "python"), prefix="irb140")
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        rows.append(
            Row(
                "generation (tau, M, C, g; C and Python)",
                f"{name}, wall",
                Value.of(wall, "s"),
                None,
                Target(limit, absolute=True),
            )
        )
        rows.append(Row("generation (tau, M, C, g; C and Python)", f"{name}, CPU", Value.of(cpu, "s")))
        files = files or generated
    return rows, files


def main() -> None:
    model = irb140()
    generation, files = generation_rows()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name, text in files.items():
            (folder / name).write_text(text)
        rows = c_rows(model, folder) + python_rows(model, folder) + generation
    print_table(rows, "Generated equations of motion (IRB-140)")
    path = write_results(
        "equations", {"machine": machine_info(("numpy", "pinocchio", "sympy")), "rows": [row.as_dict() for row in rows]}
    )
    print(f"\nwritten: {shown(path)}")


if __name__ == "__main__":
    main()
