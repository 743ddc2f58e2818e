"""The generated C against Pinocchio's CppADCodeGen kernels, both compiled here and timed in one process.

    .venv/bin/python bench/bench_cpp.py            # IRB-140, UR5, Panda, Baxter, 2 random chains (minutes)
    .venv/bin/python bench/bench_cpp.py --arms IRB-140 --blocks 100

For each arm, the `equations` tool's C (``generate(model, ("c",), what=QUANTITIES)``:
``arm_tau``, ``arm_M``, ``arm_dtau``, ``arm_qdd``, ``arm_dqdd``, ``arm_Minv``) against the
CodeGen kernels of Pinocchio 4 (``pinocchio/codegen/cppadcg-algo.hpp``: CodeGenRNEA,
CodeGenCRBA, CodeGenRNEADerivatives, CodeGenABA, CodeGenABADerivatives, CodeGenMinv) for
the same quantities. Both are C compiled by the same gcc with the same flags (``FLAGS``)
into shared libraries, ours by this script, Pinocchio's by CppADCodeGen in the driver
(bench_cpp_driver.cpp, compiled once per run and kept in a cache folder), and called
through a function pointer, in alternating blocks over the same random states. Prints one
table (ns per call, best block and median; ratio ours / CodeGen's: the median of the
blocks' ratios, each block's two timed back to back) and writes bench/results/cpp.json.

The two compute the same thing, checked before anything is timed: the driver prints both
results for one state, and this script compares each with the package's ``rnea``,
``mass_matrix``, ``rnea_derivatives``, ``forward_dynamics``,
``forward_dynamics_derivatives`` and ``inverse_mass_matrix`` (1e-9 relative to the
largest entry). Pinocchio has no friction, so the arms are taken without it (the UR5's and
the Panda's URDFs have joint damping); armature is in both. Pinocchio's RNEA and ABA
derivatives also return M and M^-1 (ours leave them to ``arm_M`` and ``arm_Minv``); its
CRBA and Minv write the upper triangle, ours the whole matrix. The random chains have no
zero in their geometry (every axis, rotation, offset and centre of mass generic).

When a compiler, Pinocchio's headers and library, Eigen's, CppAD's or CppADCodeGen's
headers are missing, the script says which and exits 0 without figures. CppAD and
CppADCodeGen come from the ``cmeel-cppad`` and ``cmeel-cppadcodegen`` wheels
(requirements/bench.txt), found in any ``cmeel.prefix`` on ``sys.path`` (so also with
``PYTHONPATH=<pip install --target folder>``).
"""

from __future__ import annotations

import argparse
import hashlib
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from common import (
    # first: puts the checkout on sys.path
    Figure,
    Row,
    Target,
    example_robot_urdf,
    machine_info,
    print_table,
    shown,
    write_results,
)

from irb140_dynamics.core import (
    forward_dynamics,
    forward_dynamics_derivatives,
    inverse_mass_matrix,
    irb140,
    mass_matrix,
    rnea,
    rnea_derivatives,
)
from irb140_dynamics.core.equations import generate
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.model.joints import Friction, Joint, Placement, snap
from irb140_dynamics.core.model.rigid_body import RigidBody
from irb140_dynamics.core.model.robot_model import RobotModel

FLAGS = "-O2"  # gcc's flags for both C sources (CppADCodeGen takes them as one argument)
# What Pinocchio's CMake target pinocchio::pinocchio_headers asks of its users (its variant
# of joint types needs the larger Boost.MPL limits), and the arity CodeGen's functors need.
PINOCCHIO_DEFINES = [
    "-DBOOST_MPL_LIMIT_LIST_SIZE=30",
    "-DBOOST_MPL_LIMIT_VECTOR_SIZE=30",
    "-DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS",
    "-DBOOST_FUSION_INVOKE_MAX_ARITY=12",
]
DRIVER = Path(__file__).with_name("bench_cpp_driver.cpp")
QUANTITIES = ("tau", "M", "dtau", "qdd", "dqdd", "Minv")
CODEGEN = {  # quantity -> Pinocchio's CodeGen kernel of it
    "tau": "CodeGenRNEA",
    "M": "CodeGenCRBA",
    "dtau": "CodeGenRNEADerivatives",
    "qdd": "CodeGenABA",
    "dqdd": "CodeGenABADerivatives",
    "Minv": "CodeGenMinv",
}
TARGETS = {"tau": 0.5, "M": 0.5, "dtau": 0.7, "qdd": 0.7, "dqdd": 0.7, "Minv": 0.7}
CHAIN_TARGETS = {"tau": 1.0, "M": 1.0}  # random chains: tau and M only
BLOCKS = 60  # alternating timed blocks per quantity
BLOCK_SECONDS = 0.004  # each side of a block, about
URDF_ARMS = {
    "UR5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "Panda": ("panda_description/urdf/panda.urdf", "panda_link8"),
    # a whole tree: both arms and the head pan, the grippers' fingers made fixed joints
    "Baxter": ("baxter_description/urdf/baxter.urdf", ""),
}
FIXED_FINGERS = re.compile(r'(<joint\s+name="[lr]_gripper_[lr]_finger_joint"\s+type=)"prismatic"')
CHAINS = {"chain-6": (6, 60), "chain-7": (7, 70)}  # name -> (joints, seed)
ARMS = ["IRB-140", *URDF_ARMS, *CHAINS]


def arms(names: list[str]) -> dict:
    """name -> the package's model of that arm, without friction."""
    found = {}
    for name in names:
        if name == "IRB-140":
            model = irb140()
        elif name in CHAINS:
            model = random_chain(*CHAINS[name])
        else:
            path, tip = URDF_ARMS[name]
            text = FIXED_FINGERS.sub(r'\1"fixed"', example_robot_urdf(path).read_text())
            model = load_urdf(text, tip_link=tip or None).model
        joints = tuple(replace(joint, friction=Friction()) for joint in model.joints)
        found[name] = replace(model, joints=joints)
    return found


def random_chain(n: int, seed: int) -> RobotModel:
    """n revolute joints in URDF form with no zero in their geometry: every origin's
    offsets and angles, every axis and centre of mass generic, inertias full."""
    rng = np.random.default_rng(seed)

    def body(mass):
        A = rng.uniform(-1.0, 1.0, (3, 3))
        S = A @ A.T * mass * 0.01 + np.eye(3) * mass * 0.002  # second moments
        I = np.trace(S) * np.eye(3) - S
        return RigidBody(
            mass,
            tuple(rng.uniform(0.02, 0.2, 3) * rng.choice([-1, 1], 3)),
            (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]),
        )

    def generic(low, high):
        return tuple(float(x) for x in rng.uniform(low, high, 3) * rng.choice([-1, 1], 3))

    joints = []
    for i in range(n):
        axis = np.array(generic(0.2, 1.0))
        joints.append(
            Joint(
                f"j{i}",
                link=body(rng.uniform(1.0, 8.0)),
                origin=Placement(generic(0.05, 0.4), generic(0.1, 1.4)),
                axis=tuple(axis / np.linalg.norm(axis)),
                armature=rng.uniform(0.05, 0.5),
            )
        )
    gravity = np.array(generic(0.2, 1.0))
    return RobotModel(tuple(joints), tuple(9.81 * gravity / np.linalg.norm(gravity)), body(0.5))


# -- what the build needs -------------------------------------------------------------------


def prefix_dirs() -> list[Path]:
    """Where pip's cmeel wheels (pin, cmeel-eigen, cmeel-cppad...) put their headers and
    libraries: a cmeel.prefix beside any folder of sys.path."""
    found = []
    for entry in sys.path:
        prefix = Path(entry or ".") / "cmeel.prefix"
        if prefix.is_dir() and prefix.resolve() not in found:
            found.append(prefix.resolve())
    return found


def _having(prefixes: list[Path], file: str) -> Path | None:
    return next((p / "include" for p in prefixes if (p / "include" / file).is_file()), None)


def build_settings() -> tuple[dict | None, str | None]:
    """({gcc, g++, includes, library}, None), or (None, what is missing)."""
    gcc, gxx = shutil.which("gcc"), shutil.which("g++")
    if gcc is None or gxx is None:
        return None, "no C and C++ compiler (gcc and g++) on PATH"
    prefixes = prefix_dirs()
    pinocchio = _having(prefixes, "pinocchio/codegen/cppadcg-algo.hpp")
    if pinocchio is None:
        return None, "no Pinocchio 4 headers with pinocchio/codegen/cppadcg-algo.hpp (the `pin` wheel)"
    library = pinocchio.parent / "lib"
    if not (library / "libpinocchio_default.so").is_file():
        return None, f"no libpinocchio_default.so in {library}"
    eigen = _having([*prefixes, Path("/usr")], "eigen3/Eigen/Dense")
    if eigen is None:
        return None, "no Eigen headers: pip install cmeel-eigen, or apt-get install libeigen3-dev"
    missing = [
        wheel
        for wheel, file in (("cmeel-cppad", "cppad/cppad.hpp"), ("cmeel-cppadcodegen", "cppad/cg.hpp"))
        if _having(prefixes, file) is None
    ]
    if missing:
        return None, f"no {' and no '.join(missing)} headers: pip install -r requirements/bench.txt"
    includes = [pinocchio, eigen / "eigen3", _having(prefixes, "cppad/cppad.hpp"), _having(prefixes, "cppad/cg.hpp")]
    return {"gcc": gcc, "g++": gxx, "includes": list(dict.fromkeys(includes)), "library": library}, None


def driver_command(settings: dict, output: Path) -> list[str]:
    """The g++ call that builds the driver."""
    library = settings["library"]
    command = [settings["g++"], "-O2", "-DNDEBUG", "-std=c++17", "-Wno-deprecated-declarations", *PINOCCHIO_DEFINES]
    command += [f"-I{folder}" for folder in settings["includes"]]
    command += [str(DRIVER), "-o", str(output), f"-L{library}", f"-Wl,-rpath,{library}"]
    return command + ["-lpinocchio_default", "-ldl", "-lm"]


def built_driver(settings: dict) -> Path:
    """The driver, compiled (minutes: Pinocchio's templates on CppAD's scalars) or taken from
    the cache folder, under a digest of its source and its g++ call."""
    digest = hashlib.sha256(DRIVER.read_bytes() + repr(driver_command(settings, Path())).encode()).hexdigest()[:16]
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "irb140_dynamics" / "bench_cpp"
    driver = cache / f"driver_{digest}"
    if not driver.is_file():
        cache.mkdir(parents=True, exist_ok=True)
        started = time.perf_counter()
        partial = driver.with_suffix(".partial")
        subprocess.run(driver_command(settings, partial), check=True)
        partial.replace(driver)
        print(f"driver built in {time.perf_counter() - started:.0f} s", file=sys.stderr)
    return driver


# -- one arm --------------------------------------------------------------------------------


def model_text(model) -> str:
    """The Pinocchio model of ours (the tests' one, test/support/pinocchio_model.py) as the
    driver reads it (see its read_model); rotation entries within 1e-15 of 0 or +-1 made
    exact and other numbers within 1e-15 of 0 made 0, as ours are (``joints.snap``):
    CodeGen then folds the same zeros and ones (cos(pi/2) is 6e-17)."""
    from test.support.pinocchio_model import build

    pm = build(model)
    kinds = {"JointModelRX": "RX", "JointModelRY": "RY", "JointModelRZ": "RZ", "JointModelPX": "PX"}
    kinds |= {"JointModelPY": "PY", "JointModelPZ": "PZ"}
    kinds |= {"JointModelRevoluteUnaligned": "RU", "JointModelPrismaticUnaligned": "PU"}
    lines = [f"gravity {_numbers(pm.gravity.linear)}"]
    for i in range(1, pm.njoints):
        joint = pm.joints[i]
        kind = kinds.get(joint.shortname())
        if kind is None:
            raise SystemExit(f"joint type {joint.shortname()} not written by this benchmark")
        axis = joint.extract().axis if kind in ("RU", "PU") else np.zeros(3)
        placement, inertia = pm.jointPlacements[i], pm.inertias[i]
        numbers = [*snap(axis), *snap(placement.rotation).flatten(), *_tiny_zero(placement.translation)]
        numbers += [inertia.mass, *_tiny_zero(inertia.lever), *_tiny_zero(inertia.inertia), pm.armature[i - 1]]
        lines.append(f"{pm.parents[i]} {kind} {_numbers(numbers)}")
    return "\n".join(lines) + "\n"


def _tiny_zero(values) -> np.ndarray:
    values = np.array(values, dtype=float).flatten()
    values[np.abs(values) < 1e-15] = 0.0
    return values


def _numbers(values) -> str:
    return " ".join(repr(float(x)) for x in np.asarray(values, dtype=float).flatten())


def arm_library(model, folder: Path, settings: dict, what=QUANTITIES) -> Path:
    """The equations tool's C of ``model`` (the quantities ``what``), compiled by gcc with
    FLAGS as a shared library."""
    for name, text in generate(model, ("c",), what=what, prefix="arm", source="bench_cpp").items():
        (folder / name).write_text(text)
    library = folder / "arm.so"
    command = [settings["gcc"], "-x", "c", FLAGS, "-fPIC", "-shared", str(folder / "arm_eom.c")]
    subprocess.run([*command, "-o", str(library), "-lm"], check=True)
    return library


def expected(model, state: np.ndarray) -> dict[str, np.ndarray]:
    """The package's values of every quantity at the state (columns q, qd, qdd, tau), in the
    driver's layouts (M and M^-1: upper triangles row by row)."""
    q, qd, qdd, tau = state.T
    upper = np.triu_indices(model.n)
    return {
        "tau": rnea(model, q, qd, qdd),
        "M": mass_matrix(model, q)[upper],
        "dtau": np.concatenate([m.flatten() for m in rnea_derivatives(model, q, qd, qdd)[:2]]),
        "qdd": forward_dynamics(model, q, qd, tau),
        "dqdd": np.concatenate([m.flatten() for m in forward_dynamics_derivatives(model, q, qd, tau)[:2]]),
        "Minv": inverse_mass_matrix(model, q)[upper],
    }


def check_same(name: str, model, lines: list[str]) -> None:
    """Both programs' results for state 0 against the package's (1e-9 of the largest entry)."""
    state = np.array([[float(x) for x in line.split()[1:]] for line in lines if line.startswith("state ")])
    for key, want in expected(model, state).items():
        got = np.array([[float(x) for x in line.split()[3:]] for line in lines if line.startswith(f"x {key} ")])
        scale = float(np.abs(want).max())
        for column, who in enumerate(("generated C", f"Pinocchio {CODEGEN[key]}")):
            error = float(np.abs(got[: len(want), column] - want).max())
            if not error <= 1e-9 * scale:
                raise SystemExit(f"{name}: {who} {key} differs from the package's by {error:.3g} (largest {scale:.3g})")


@dataclass(frozen=True)
class PairedRow(Row):
    """A Row whose ratio is the median of the blocks' ratios (each block's two timed back to
    back, so a load that comes and goes weighs on both)."""

    paired: float = math.nan

    @property
    def ratio(self) -> float:
        return self.paired


def rows_for(name: str, model, folder: Path, driver: Path, settings: dict, blocks: int) -> list[Row]:
    started = time.perf_counter()
    library = arm_library(model, folder, settings)
    (folder / "arm.txt").write_text(model_text(model))
    command = [str(driver), str(folder / "arm.txt"), str(library), settings["gcc"], FLAGS, str(BLOCK_SECONDS)]
    lines = subprocess.run(
        [*command, str(blocks)], check=True, capture_output=True, text=True, cwd=folder
    ).stdout.splitlines()
    print(f"{name}: built, checked and timed in {time.perf_counter() - started:.0f} s", file=sys.stderr)
    check_same(name, model, lines)
    group = f"{name} ({model.n} joints), ns per call in one C++ process"
    targets = CHAIN_TARGETS if name in CHAINS else TARGETS
    rows = []
    for quantity in QUANTITIES:
        times = [[float(x) for x in line.split()[2:]] for line in lines if line.startswith(f"time {quantity} ")]
        ours, theirs = (Figure.cost([t[k] for t in times], "ns") for k in (0, 1))
        paired = statistics.median(a / b for a, b in times)
        target = Target(targets[quantity]) if quantity in targets else None
        label = f"generated C {quantity} vs Pinocchio {CODEGEN[quantity]}"
        rows.append(PairedRow(group, label, ours, theirs, target, paired=paired))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--arms", nargs="+", default=ARMS, choices=ARMS)
    parser.add_argument("--blocks", type=int, default=BLOCKS, help=f"timed blocks per quantity (default {BLOCKS})")
    options = parser.parse_args()
    settings, why_not = build_settings()
    if why_not is not None:
        print(f"bench_cpp: cannot build the C++ benchmark: {why_not}; nothing measured")
        return
    driver = built_driver(settings)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, model in arms(options.arms).items():
            folder = Path(tmp) / name
            folder.mkdir()
            rows += rows_for(name, model, folder, driver, settings, options.blocks)
    print_table(rows, f"Generated C vs Pinocchio's CppADCodeGen kernels (gcc {FLAGS}, both in one process)")
    results = {
        "machine": machine_info(("numpy", "pinocchio", "sympy")),
        "flags": FLAGS,
        "blocks": options.blocks,
        "block_seconds": BLOCK_SECONDS,
        "rows": [row.as_dict() for row in rows],
    }
    print(f"\nwritten: {shown(write_results('cpp', results))}")


if __name__ == "__main__":
    main()
