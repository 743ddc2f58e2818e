"""The generated C against Pinocchio's C++, both compiled here and timed in one process.

    .venv/bin/python bench/bench_cpp.py            # IRB-140, UR5, Panda, Baxter (a few minutes)
    .venv/bin/python bench/bench_cpp.py --arms IRB-140

For each arm, the `equations` tool's C (``generate(model, ("c",), what=("tau", "M"))``:
``<arm>_tau(q, qd, qdd, tau)`` and ``<arm>_M(q, M)``) and Pinocchio's C++ ``rnea`` and
``crba`` (headers and ``libpinocchio_default`` of the `pin` wheel, Eigen's headers from
the `cmeel-eigen` wheel or Debian's `libeigen3-dev`) are compiled by the same compiler with
the same flags (``FLAGS``) into one driver, which times each function in alternating
blocks over the same random states. Prints one table (ns per call; ratio ours / Pinocchio's;
target <= 0.2x) and writes bench/results/cpp.json.

The two compute the same thing, checked before anything is timed: the driver prints both
results for one state and this script compares them with the package's ``rnea`` and
``mass_matrix`` (to 1e-9). Pinocchio has no friction, so the arms are taken without it
(the UR5's and the Panda's URDFs have joint damping); armature is in both. The Pinocchio
model is built from ours joint by joint (test/support/pinocchio_model.py: the model the
tests check against), and written out as C++ calls of Pinocchio's model API, so that no
URDF parser takes part.

When a compiler, Pinocchio's headers and library or Eigen's headers are missing, the script
says which and exits 0 without figures.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from common import (
    # first: puts the checkout on sys.path
    REPO,
    Figure,
    Row,
    Target,
    example_robot_urdf,
    machine_info,
    print_table,
    shown,
    write_results,
)

from irb140_dynamics.core import irb140, mass_matrix, rnea
from irb140_dynamics.core.equations import generate
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.model.joints import Friction

FLAGS = ["-O2", "-DNDEBUG"]  # the same for the generated C and Pinocchio (one g++ call)
# What Pinocchio's CMake target pinocchio::pinocchio_headers asks of its users (its variant
# of joint types needs the larger Boost.MPL limits).
PINOCCHIO_DEFINES = [
    "-DBOOST_MPL_LIMIT_LIST_SIZE=30",
    "-DBOOST_MPL_LIMIT_VECTOR_SIZE=30",
    "-DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS",
    "-DBOOST_FUSION_INVOKE_MAX_ARITY=12",
]
STATES = 1024  # the loops cycle through these (no constant folding of one state)
BLOCKS = 25  # alternating timed blocks per function
CALLS = 20_000  # calls per block
SEED = 140
TARGET = 0.2
URDF_ARMS = {
    "UR5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "Panda": ("panda_description/urdf/panda.urdf", "panda_link8"),
    # a whole tree: both arms and the head pan, the grippers' fingers made fixed joints
    "Baxter": ("baxter_description/urdf/baxter.urdf", ""),
}
FIXED_FINGERS = re.compile(r'(<joint\s+name="[lr]_gripper_[lr]_finger_joint"\s+type=)"prismatic"')


def arms(names: list[str]) -> dict:
    """name -> the package's model of that arm, without friction."""
    found = {}
    for name in names:
        if name == "IRB-140":
            model = irb140()
        else:
            path, tip = URDF_ARMS[name]
            text = FIXED_FINGERS.sub(r'\1"fixed"', example_robot_urdf(path).read_text())
            model = load_urdf(text, tip_link=tip or None).model
        joints = tuple(replace(joint, friction=Friction()) for joint in model.joints)
        found[name] = replace(model, joints=joints)
    return found


# -- what the build needs -------------------------------------------------------------------


def prefix_dirs() -> list[Path]:
    """Where pip's cmeel wheels (pin, cmeel-eigen, cmeel-boost) put their headers and libraries."""
    site = Path(sysconfig.get_paths()["purelib"])
    return [p for p in (site / "cmeel.prefix",) if p.is_dir()]


def build_settings() -> tuple[list[str], str | None]:
    """(g++ arguments for headers and libraries, None) or ([], why it cannot build)."""
    compiler = shutil.which("g++") or shutil.which("c++")
    if compiler is None:
        return [], "no C++ compiler (g++) on PATH"
    prefixes = prefix_dirs()
    pinocchio = [p for p in prefixes if (p / "include/pinocchio/algorithm/rnea.hpp").is_file()]
    if not pinocchio:
        return [], "no Pinocchio headers (the `pin` wheel's cmeel.prefix/include/pinocchio)"
    library = pinocchio[0] / "lib"
    if not (library / "libpinocchio_default.so").is_file():
        return [], f"no libpinocchio_default.so in {library}"
    eigen = [p / "include/eigen3" for p in prefixes if (p / "include/eigen3/Eigen/Dense").is_file()]
    eigen += [Path("/usr/include/eigen3")] if Path("/usr/include/eigen3/Eigen/Dense").is_file() else []
    if not eigen:
        return [], "no Eigen headers: pip install cmeel-eigen, or apt-get install libeigen3-dev"
    include = pinocchio[0] / "include"
    return [
        compiler,
        *PINOCCHIO_DEFINES,
        f"-I{include}",
        f"-I{eigen[0]}",
        f"-L{library}",
        f"-Wl,-rpath,{library}",
    ], None


# -- the driver -------------------------------------------------------------------------------


def pinocchio_model_code(model) -> str:
    """C++ statements that build in ``model`` (a pinocchio::Model) the Pinocchio model of ours."""
    from test.support.pinocchio_model import build

    pm = build(model)
    lines = [f"model.gravity.linear() << {_list(pm.gravity.linear)};"]
    for i in range(1, pm.njoints):
        joint = pm.joints[i]
        kind = joint.shortname()
        if kind in ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelPX", "JointModelPY", "JointModelPZ"):
            make = f"pinocchio::{kind}()"
        elif kind in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"):
            make = f"pinocchio::{kind}(Eigen::Vector3d({_list(joint.extract().axis, ', ')}))"
        else:
            raise SystemExit(f"joint type {kind} not written by this benchmark")
        placement = pm.jointPlacements[i]
        inertia = pm.inertias[i]
        lines += [
            "{",
            f"  Eigen::Matrix3d R; R << {_list(placement.rotation.flatten())};",
            f"  Eigen::Vector3d p({_list(placement.translation, ', ')});",
            f'  auto id = model.addJoint({pm.parents[i]}, {make}, pinocchio::SE3(R, p), "j{i}");',
            f"  Eigen::Matrix3d I; I << {_list(inertia.inertia.flatten())};",
            f"  Eigen::Vector3d c({_list(inertia.lever, ', ')});",
            f"  model.appendBodyToJoint(id, pinocchio::Inertia({float(inertia.mass)!r}, c, I), pinocchio::SE3::Identity());",
            f"  model.armature[{i - 1}] = {float(pm.armature[i - 1])!r};",
            "}",
        ]
    return "\n".join("    " + line for line in lines)


def _list(values, separator: str = ", ") -> str:
    return separator.join(repr(float(x)) for x in np.asarray(values).flatten())


DRIVER = r"""
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include "arm_eom.h"

static const int N = ARM_N;

template <class F> static double block(long calls, F f)
{
    auto t0 = std::chrono::steady_clock::now();
    for (long k = 0; k < calls; ++k) f(k % STATES);
    auto t1 = std::chrono::steady_clock::now();
    return std::chrono::duration<double>(t1 - t0).count() / calls;
}

int main(int argc, char **argv)
{
    if (argc != 3) return 2;
    long calls = atol(argv[1]);
    int blocks = atoi(argv[2]);
    pinocchio::Model model;
@MODEL@
    pinocchio::Data data(model);
    static double q[STATES][N], qd[STATES][N], qdd[STATES][N];
    unsigned s = 12345u;
    for (int i = 0; i < STATES; ++i)
        for (int j = 0; j < N; ++j) {
            s = s * 1103515245u + 12345u; q[i][j] = (double)(s >> 8) / 16777216.0 * 6.0 - 3.0;
            s = s * 1103515245u + 12345u; qd[i][j] = (double)(s >> 8) / 16777216.0 * 4.0 - 2.0;
            s = s * 1103515245u + 12345u; qdd[i][j] = (double)(s >> 8) / 16777216.0 * 10.0 - 5.0;
        }
    double tau[N], M[N * N], sum = 0.0;
    typedef Eigen::Map<const Eigen::VectorXd> In;

    /* the check: both results for state 0, and the state itself */
    arm_tau(q[0], qd[0], qdd[0], tau);
    arm_M(q[0], M);
    pinocchio::rnea(model, data, In(q[0], N), In(qd[0], N), In(qdd[0], N));
    pinocchio::crba(model, data, In(q[0], N));
    data.M.triangularView<Eigen::StrictlyLower>() = data.M.transpose().triangularView<Eigen::StrictlyLower>();
    for (int j = 0; j < N; ++j) printf("q %.17g %.17g %.17g\n", q[0][j], qd[0][j], qdd[0][j]);
    for (int j = 0; j < N; ++j) printf("tau %.17g %.17g\n", tau[j], data.tau[j]);
    for (int j = 0; j < N * N; ++j) printf("M %.17g %.17g\n", M[j], data.M(j / N, j % N));

    auto ours_tau = [&](int i) { arm_tau(q[i], qd[i], qdd[i], tau); sum += tau[i % N]; };
    auto ours_M = [&](int i) { arm_M(q[i], M); sum += M[i % (N * N)]; };
    auto pin_rnea = [&](int i) {
        pinocchio::rnea(model, data, In(q[i], N), In(qd[i], N), In(qdd[i], N)); sum += data.tau[i % N];
    };
    auto pin_crba = [&](int i) {
        pinocchio::crba(model, data, In(q[i], N)); sum += data.M(0, i % N);
    };
    for (int b = 0; b < blocks; ++b) {
        printf("time %.12e %.12e %.12e %.12e\n", block(calls, ours_tau), block(calls, pin_rnea),
               block(calls, ours_M), block(calls, pin_crba));
    }
    fprintf(stderr, "%g\n", sum);
    return 0;
}
"""


def generated_c(model) -> dict[str, str]:
    """The equations tool's C of tau and M; kept in bench/data/ (the derivation takes minutes
    for 7 joints), under a digest of the model and of the code that derives it."""
    package = REPO / "irb140_dynamics/core"
    sources = sorted((package / "equations").glob("*.py")) + sorted((package / "algorithms").glob("*.py"))
    digest = hashlib.sha256(repr(model).encode() + b"".join(p.read_bytes() for p in sources)).hexdigest()[:16]
    cached = REPO / "bench/data" / f"cpp_{digest}.json"
    if cached.is_file():
        return json.loads(cached.read_text())
    files = generate(model, ("c",), what=("tau", "M"), prefix="arm", source="bench_cpp")
    cached.parent.mkdir(parents=True, exist_ok=True)
    cached.write_text(json.dumps(files))
    return files


def build_driver(model, folder: Path, settings: list[str]) -> Path:
    files = generated_c(model)
    for name, text in files.items():
        (folder / name).write_text(text)
    (folder / "driver.cpp").write_text(DRIVER.replace("@MODEL@", pinocchio_model_code(model)))
    driver = folder / "driver"
    compiler, *paths = settings
    # the generated C compiled as C++ by the same g++ call, with the same flags
    command = [compiler, *FLAGS, f"-DSTATES={STATES}", "-std=c++17", *paths, f"-I{folder}"]
    command += ["-x", "c++", str(folder / "arm_eom.c"), str(folder / "driver.cpp"), "-o", str(driver)]
    command += ["-lpinocchio_default", "-lm"]
    subprocess.run(command, check=True)
    return driver


def check_same(name: str, model, lines: list[str]) -> None:
    """Both programs' results for state 0 against the package's rnea and mass_matrix."""
    state = np.array([[float(x) for x in line.split()[1:]] for line in lines if line.startswith("q ")])
    q, qd, qdd = state.T
    expected = {"tau": rnea(model, q, qd, qdd), "M": mass_matrix(model, q).flatten()}
    for key, want in expected.items():
        got = np.array([[float(x) for x in line.split()[1:]] for line in lines if line.startswith(f"{key} ")])
        scale = max(1.0, float(np.abs(want).max()))
        for column, who in enumerate(("generated C", "Pinocchio C++")):
            error = float(np.abs(got[:, column] - want).max())
            if error > 1e-9 * scale:
                raise SystemExit(f"{name}: {who} {key} differs from the package's by {error:.3g}")


def rows_for(name: str, model, folder: Path, settings: list[str]) -> list[Row]:
    started = time.perf_counter()
    driver = build_driver(model, folder, settings)
    print(f"{name}: generated and built in {time.perf_counter() - started:.0f} s", file=sys.stderr)
    lines = subprocess.run(
        [str(driver), str(CALLS), str(BLOCKS)], check=True, capture_output=True, text=True
    ).stdout.splitlines()
    check_same(name, model, lines)
    times = np.array([[float(x) for x in line.split()[1:]] for line in lines if line.startswith("time ")])
    tau, pin_rnea, M, pin_crba = (Figure.cost([float(x) for x in times[:, k]], "ns") for k in range(4))
    group = f"{name} ({model.n} joints), ns per call in one C++ process"
    return [
        Row(group, "generated C tau vs Pinocchio C++ rnea", tau, pin_rnea, Target(TARGET)),
        Row(group, "generated C M vs Pinocchio C++ crba", M, pin_crba, Target(TARGET)),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--arms", nargs="+", default=["IRB-140", *URDF_ARMS], choices=["IRB-140", *URDF_ARMS])
    options = parser.parse_args()
    settings, why_not = build_settings()
    if why_not is not None:
        print(f"bench_cpp: cannot build the C++ benchmark: {why_not}; nothing measured")
        return
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, model in arms(options.arms).items():
            folder = Path(tmp) / name
            folder.mkdir()
            rows += rows_for(name, model, folder, settings)
    print_table(rows, f"Generated C vs Pinocchio's C++ (g++ {' '.join(FLAGS)}, both in one process)")
    results = {
        "machine": machine_info(("numpy", "pinocchio", "sympy")),
        "flags": FLAGS,
        "rows": [row.as_dict() for row in rows],
    }
    print(f"\nwritten: {shown(write_results('cpp', results))}")


if __name__ == "__main__":
    main()
