"""Hostile command lines for the tools (identify, excitation, export_urdf, record), seeded:
the same seed gives the same cases. Shared by test/tools/test_fuzz_tools.py (a few dozen
cases) and bench/fuzz_tools.py (thousands).

Each case is a tool and its arguments, drawn from pools of bad and good values: numbers
(NaN, inf, negative, huge, not a number), output paths (under /proc, under a file, in a
missing folder, a folder, a device, a name too long, empty), input files (missing, empty,
binary, a 300 kB field, efforts of 1e300, a device, a folder that is no bag), topic names
and ROS parameters. What every case must give (``check``): exit status 0, 1 or 2; a
failure is one line under 300 characters on stderr, ``<tool>: error: ...`` (never an
internal error or a traceback), and leaves the working folder as it was; a success wrote
what it says.
"""

from __future__ import annotations

import contextlib
import io
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

NUMBERS_BAD = ["nan", "inf", "-inf", "-5", "1e300", "-1e-300", "abc", "", "0x10", "1e", "--", "1,5"]
INTEGERS_BAD = ["nan", "-5", "1.5", "1e9999", "", "abc", str(2**70), "0x10"]
OUTPUTS_BAD = [
    "/proc/out.yaml",
    "afile/out.yaml",
    "missing/deeper/out.yaml",
    "folder",
    "/dev/null",
    "",
    ".",
    "x" * 300 + ".yaml",
    "/proc/self/out.yaml",
    "folder/",
]
INPUTS_BAD = [
    "missing.csv",
    "empty.csv",
    "binary.csv",
    "field.csv",
    "absurd.csv",
    "rest.csv",
    "/dev/zero",
    "/dev/null",
    "folder",
    "notabag.mcap",
    "noheader.csv",
    "afile",
    "/proc/self/status",
]
TOPICS_BAD = ["bad name", "/a//b", "1abc", "", "~~", "/joint_states/", "{x}", "a" * 300]
PARAMS_BAD = [
    "joint_2.link.mass:=-1.0",
    "joint_2.link.mass:=nan",
    "joint_1.velocity_limit:=inf",
    "joint_2.link.com:=[0.1]",
    "payload.mass:=1e300",
    "gravity:=[0.0, 0.0]",
    "nonsense",
    "joint_7.x:=1.0",
]


@dataclass
class Case:
    tool: str
    argv: list[str]
    writes: list[str] = field(default_factory=list)  # outputs on success, as typed


def prepare(folder: Path) -> None:
    """The inputs the cases name, in ``folder`` (the working folder of the cases)."""
    names = [f"joint_{i}" for i in range(1, 7)]
    header = ",".join(["time"] + [f"position_{n}" for n in names] + [f"effort_{n}" for n in names])
    rows = lambda effort: "\n".join(  # noqa: E731
        ",".join([f"{k * 0.004:.3f}"] + ["0.1"] * 6 + [effort] * 6) for k in range(400)
    )
    (folder / "empty.csv").write_text("")
    (folder / "binary.csv").write_bytes(bytes(range(256)) * 8)
    (folder / "field.csv").write_text(header + "\n" + "1" * 300_000 + ",0" * 12 + "\n")
    (folder / "absurd.csv").write_text(header + "\n" + rows("1e300") + "\n")
    (folder / "rest.csv").write_text(header + "\n" + rows("1.0") + "\n")
    (folder / "noheader.csv").write_text(rows("1.0") + "\n")
    (folder / "notabag.mcap").write_bytes(os.urandom(2048))
    (folder / "afile").write_text("a file, not a folder\n")
    (folder / "folder").mkdir(exist_ok=True)
    from irb140_dynamics.package_files import default_config_path

    (folder / "params.yaml").write_text(default_config_path().read_text())


class ToolFuzzer:
    """Cases drawn from the pools: each has at least one bad value (so that it fails fast)
    unless ``valid_share`` > 0 lets some be all good (bench: they run the whole tool)."""

    def __init__(self, seed: int, valid_share: float = 0.0):
        self.rng = np.random.default_rng(seed)
        self.valid_share = valid_share
        self.count = 0

    def pick(self, pool):
        return pool[int(self.rng.integers(len(pool)))]

    def case(self) -> Case:
        self.count += 1
        tool = self.pick(["identify", "excitation", "export_urdf", "record"])
        return getattr(self, tool)(self.rng.random() >= self.valid_share)

    def _options(self, options: dict, bad: bool) -> list[str]:
        """``options``: name -> (good values, bad values); one or more made bad when ``bad``."""
        names = list(options)
        chosen = [n for n in names if self.rng.random() < 0.5]
        broken = set(self.rng.choice(names, size=int(self.rng.integers(1, 3)), replace=False)) if bad else set()
        argv = []
        for name in names:
            if name not in chosen and name not in broken:
                continue
            good, worse = options[name]
            value = self.pick(worse if name in broken else good)
            argv += [name, value] if name.startswith("-") else [value]
        return argv

    def identify(self, bad: bool) -> Case:
        options = {
            "recording": (["rest.csv"], INPUTS_BAD),
            "--out": (["out.yaml", "folder/out.yaml"], OUTPUTS_BAD),
            "--cutoff": (["10", "3.5"], NUMBERS_BAD + ["0"]),
            "--held-out": (["0.2", "0.5"], NUMBERS_BAD + ["0", "1", "1.5"]),
            "--min-speed": (["0.05"], NUMBERS_BAD),
            "--prior-weight": (["1", "0.1"], NUMBERS_BAD + ["0"]),
            "--plots": (["plots", "folder/plots"], OUTPUTS_BAD),
            "--params-file": (["params.yaml"], ["missing.yaml", "binary.csv", "/dev/zero", "folder", "absurd.csv"]),
            "--topic": (["/joint_states"], TOPICS_BAD),
        }
        argv = self._options(options, bad)
        if not any(a in ("--out",) for a in argv):
            argv += ["--out", "out.yaml"]
        if not argv or argv[0].startswith("-"):
            argv = ["rest.csv", *argv]
        return Case("identify", argv + ["--quiet"])  # rest.csv never fits: nothing moves

    def excitation(self, bad: bool) -> Case:
        options = {
            "--out": (["traj.yaml"], OUTPUTS_BAD),
            "--rate": (["10"], NUMBERS_BAD + ["0", "1e9"]),
            "--period": (["2"], NUMBERS_BAD + ["0"]),
            "--harmonics": (["2"], INTEGERS_BAD + ["0", "1000"]),
            "--periods": (["1"], INTEGERS_BAD + ["0"]),
            "--margin": (["0.1"], NUMBERS_BAD + ["0.5", "-0.1"]),
            "--seed": (["3"], INTEGERS_BAD),
            "--iterations": (["0"], INTEGERS_BAD),
            "--params-file": (["params.yaml"], ["missing.yaml", "binary.csv", "folder"]),
        }
        argv = self._options(options, bad)
        if "--out" not in argv:
            argv += ["--out", "traj.yaml"]
        if "--iterations" not in argv:
            argv += ["--iterations", "0"]
        return Case("excitation", argv, ["traj.yaml"])

    def export_urdf(self, bad: bool) -> Case:
        argv = ["export_urdf"]
        if bad and self.rng.random() < 0.5:
            argv += ["--out", self.pick(OUTPUTS_BAD)]
        elif self.rng.random() < 0.5:
            argv += ["--out", "arm.urdf"]
        if bad and (len(argv) == 1 or self.rng.random() < 0.5):
            argv += ["--ros-args", "-p", self.pick(PARAMS_BAD)]
        return Case("export_urdf", argv)

    def record(self, bad: bool) -> Case:  # always bad: a good one would wait for a publisher
        options = {
            "--out": (["bag"], [x for x in OUTPUTS_BAD if not x.startswith("missing/")] + ["afile", "folder"]),
            "--topic": (["/joint_states"], TOPICS_BAD),
            "--duration": (["1"], NUMBERS_BAD),
            "--depth": (["10"], INTEGERS_BAD + ["0"]),
            "--reference": (["/id_node/reference"], TOPICS_BAD),
            "--tail": (["1"], NUMBERS_BAD),
        }
        argv = self._options(options, True)
        if "--out" not in argv:
            argv += ["--out", "bag"]
        return Case("record", ["record", *argv])


def snapshot(folder: Path) -> dict[str, float]:
    """Every file and folder under ``folder`` (hidden ones too), a file with its modification
    time (a folder's changes when the tools try it for writing: a file made and removed)."""
    return {str(p.relative_to(folder)): 0.0 if p.is_dir() else p.stat().st_mtime for p in folder.rglob("*")}


def run_case(case: Case, folder: Path) -> tuple[int, str, str]:
    """Run the case's main() in this process, in ``folder``: (status, stdout, stderr)."""
    import importlib

    main = importlib.import_module(f"irb140_dynamics.tools.{case.tool}").main
    out, err = io.StringIO(), io.StringIO()
    here = os.getcwd()
    os.chdir(folder)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main(list(case.argv))
    finally:
        os.chdir(here)
    return status, out.getvalue(), err.getvalue()


def check(case: Case, status: int, stdout: str, stderr: str, before: dict, after: dict) -> str | None:
    """What is wrong with the outcome of ``case`` (None: nothing)."""
    if "Traceback" in stdout + stderr:
        return "a traceback"
    if status not in (0, 1, 2):
        return f"exit status {status}"
    lines = [line for line in stderr.splitlines() if line.strip()]
    if status != 0:
        errors = [line for line in lines if ": error: " in line]
        if len(errors) != 1 or not errors[0].startswith(f"{case.tool}: error: "):
            return f"not one error line: {lines}"
        if len(errors[0]) >= 300:
            return f"an error line of {len(errors[0])} characters"
        if "internal error" in errors[0]:
            return errors[0]
        if before != after:
            changed = sorted(set(before.items()) ^ set(after.items()))
            return f"the folder changed on a failure: {changed[:5]}"
    return None
