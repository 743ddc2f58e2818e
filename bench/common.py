"""Shared helpers of the benchmark scripts: timing, the results table, JSON and machine info.

A benchmark measures a figure of ours and of a baseline in the same run and reports their
ratio (ours / baseline) against a target. Importing this module also puts the repository
root first on ``sys.path``, so ``.venv/bin/python bench/<script>.py`` runs on the checkout.
"""

from __future__ import annotations

import json
import math
import os
import platform
import statistics
import subprocess
import sys
import timeit
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
# where write_results puts the JSON (the doc-test harness points it elsewhere)
RESULTS = Path(os.environ.get("IRB140_BENCH_RESULTS") or REPO / "bench" / "results")

if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


# -- measuring --------------------------------------------------------------------------


def seconds_per_call(
    fn: Callable[[], object], blocks: int = 25, block_seconds: float = 0.02, number: int | None = None
) -> list[float]:
    """Seconds per call of ``fn`` in each of ``blocks`` timed blocks (garbage collector off).

    Each block makes ``number`` calls; by default as many as take about ``block_seconds``,
    found by ``timeit``'s autorange, which also warms ``fn`` up. With ``number`` given,
    ``fn`` is called once untimed first.
    """
    timer = timeit.Timer(fn)
    if number is None:
        calls, elapsed = timer.autorange()
        number = max(1, round(calls * block_seconds / elapsed))
    else:
        fn()
    return [t / number for t in timer.repeat(repeat=blocks, number=number)]


@dataclass(frozen=True)
class Figure:
    """A measured quantity: its best value over the timed blocks, and their median."""

    best: float
    median: float
    unit: str

    @classmethod
    def cost(cls, samples: Sequence[float], unit: str = "us") -> Figure:
        """Seconds per call (lower is better) as nanoseconds, microseconds or milliseconds."""
        scale = {"ns": 1e9, "us": 1e6, "ms": 1e3, "s": 1.0}[unit]
        return cls(min(samples) * scale, statistics.median(samples) * scale, unit)

    @classmethod
    def rate(cls, samples: Sequence[float], items: int, unit: str = "states/s") -> Figure:
        """Items per second (higher is better) of calls that each process ``items``."""
        return cls(items / min(samples), items / statistics.median(samples), unit)

    def __str__(self) -> str:
        return f"{_number(self.best)} {self.unit} (med {_number(self.median)})"


@dataclass(frozen=True)
class Target:
    """The ratio ours / baseline a figure must reach: at most ``limit``, or at least.

    ``absolute``: the limit is on our figure itself (its best value), not on the ratio,
    e.g. ``Target(0, absolute=True)``: no message lost.
    """

    limit: float
    at_least: bool = False
    absolute: bool = False

    def met(self, value: float) -> bool:
        """``value``: the ratio, or our figure for an absolute target."""
        return value >= self.limit if self.at_least else value <= self.limit

    def shortfall(self, ratio: float) -> float:
        """How many times worse than the target the ratio is (1 or less: met)."""
        return self.limit / ratio if self.at_least else ratio / self.limit

    def __str__(self) -> str:
        return f"{'>=' if self.at_least else '<='} {self.limit:g}{'' if self.absolute else 'x'}"


@dataclass(frozen=True)
class Row:
    """One line of the results table; ``group`` heads a section of the table."""

    group: str
    name: str
    ours: Figure
    baseline: Figure | None = None
    target: Target | None = None

    @property
    def ratio(self) -> float | None:
        """ours / baseline on the best values (None without a baseline or when it is 0)."""
        return None if self.baseline is None else _divide(self.ours.best, self.baseline.best)

    @property
    def met(self) -> bool | None:
        if self.target is None:
            return None
        value = self.ours.best if self.target.absolute else self.ratio
        return None if value is None else self.target.met(value)

    def as_dict(self) -> dict:
        row = {"group": self.group, "name": self.name, "ours": vars(self.ours)}
        if self.baseline is not None:
            row["baseline"] = vars(self.baseline)
            row["ratio"] = self.ratio
            row["ratio_of_medians"] = _divide(self.ours.median, self.baseline.median)
        if self.target is not None:
            row["target"] = {"limit": self.target.limit, "at_least": self.target.at_least}
            if self.target.absolute:
                row["target"]["absolute"] = True
            row["met"] = self.met
        return row


@dataclass(frozen=True)
class Value(Figure):
    """One measured number (best = median = it), printed alone."""

    @classmethod
    def of(cls, x: float, unit: str) -> Value:
        return cls(float(x), float(x), unit)

    def __str__(self) -> str:
        if self.unit in ("msgs", "calls"):
            return f"{self.best:.0f} {self.unit}"
        return f"{_number(self.best)} {self.unit}"


@dataclass(frozen=True)
class NotMeasured(Figure):
    """A figure that could not be taken, and why."""

    reason: str = ""

    def __str__(self) -> str:
        return f"not measured: {self.reason}"


def _divide(a: float | None, b: float | None) -> float | None:
    return None if a is None or b is None or b == 0 else a / b


# -- reporting --------------------------------------------------------------------------

_COLUMNS = ("name", "ours", "baseline", "ratio", "target", "result")


def print_table(rows: Iterable[Row], title: str) -> None:
    """The rows as a plain-text table, one section per group, then any missed targets."""
    rows = list(rows)
    cells = [_cells(row) for row in rows]
    widths = [max(len(c[i]) for c in [_COLUMNS, *cells]) for i in range(len(_COLUMNS))]
    rule = "-+-".join("-" * w for w in widths)
    print(f"\n{title}\n")
    print(" | ".join(h.ljust(w) for h, w in zip(_COLUMNS, widths)))
    group = None
    for row, line in zip(rows, cells):
        if row.group != group:
            group = row.group
            print(rule)
            print(f"[{group}]")
        print(" | ".join(c.ljust(w) for c, w in zip(line, widths)))
    print(rule)
    missed = [row for row in rows if row.met is False]
    for row in missed:
        if row.target.absolute:
            print(f"MISSED: {row.name}: {row.ours}, target {row.target}")
            continue
        print(
            f"MISSED: {row.name}: ratio {_ratio(row.ratio)}, target {row.target}, "
            f"{row.target.shortfall(row.ratio):.2f}x off"
        )
    checked = sum(row.met is not None for row in rows)
    print(f"{checked - len(missed)} of {checked} targets met")


def _cells(row: Row) -> tuple[str, ...]:
    result = "-" if row.met is None else ("met" if row.met else "MISSED")
    target = "-" if row.target is None else str(row.target)
    baseline = "-" if row.baseline is None else str(row.baseline)
    ratio = "-" if row.ratio is None else _ratio(row.ratio)
    return (row.name, str(row.ours), baseline, ratio, target, result)


def _number(x: float) -> str:
    """Three significant digits, no exponent; k and M suffixes from 10,000 on."""
    for scale, suffix in ((1e6, "M"), (1e3, "k")):
        if abs(x) >= max(scale, 1e4):
            return _number(x / scale) + suffix
    if x == 0:
        return "0"
    decimals = max(0, 2 - math.floor(math.log10(abs(x))))
    return f"{x:.{decimals}f}"


def _ratio(ratio: float) -> str:
    return f"1/{1 / ratio:.0f}x" if 0 < ratio < 0.1 else f"{ratio:.2f}x"


def machine_info(modules: Sequence[str] = ("numpy",)) -> dict:
    """CPU, OS, Python, the versions of ``modules``, the checkout's commit and the date."""
    info = {
        "cpu": _cpu_model(),
        "logical_cpus": os.cpu_count(),
        "platform": platform.platform(),
        "python": platform.python_version(),
    }
    for module in modules:
        info[module] = _version(module)
    info["git_commit"] = _git_commit()
    info["date"] = datetime.now(UTC).isoformat(timespec="seconds")
    return info


def shown(path: Path) -> Path:
    """``path`` as printed: relative to the checkout when inside it."""
    return path.relative_to(REPO) if path.is_relative_to(REPO) else path


def write_results(name: str, results: dict) -> Path:
    """Write ``results`` as bench/results/<name>.json (atomically) and return the path."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(results, indent=2) + "\n")
    os.replace(tmp, path)
    return path


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def _version(module: str) -> str | None:
    """The imported module's ``__version__``, else its distribution's version."""
    try:
        return str(__import__(module).__version__)
    except (ImportError, AttributeError):
        pass
    try:
        return metadata.version(module)
    except metadata.PackageNotFoundError:
        return None


def _git_commit() -> str | None:
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain"], cwd=REPO, capture_output=True, text=True, check=True
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return commit + ("-dirty" if dirty else "")


def set_priority(priority: int) -> bool:
    """The calling thread on SCHED_FIFO at ``priority`` (0: back to normal scheduling); False
    if not allowed. Threads and processes it starts inherit it: they call set_priority(0)."""
    try:
        if priority:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
        else:
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        return True
    except (OSError, AttributeError):  # not permitted (no CAP_SYS_NICE), or not Linux
        return False


def example_robot_urdf(path: str) -> Path:
    """An example-robot-data URDF file, by its path under the package's robots/ folder
    (e.g. "ur_description/urdf/ur5_robot.urdf")."""
    files = metadata.distribution("example-robot-data").files or ()
    (found,) = [f for f in files if str(f).split("robots/")[-1] == path]
    return Path(found.locate())
