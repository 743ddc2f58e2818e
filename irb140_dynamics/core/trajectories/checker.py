"""A model with the limits its trajectories are held to, built once and used for every
trajectory a service checks or re-times (trajectory_check_node's), and a report in the
terms a monitor shows: a level and one figure per joint and limit.

Deriving torque limits (where the params leave them at 0) sweeps the workspace and takes
seconds: ``TrajectoryChecker.of`` takes those of a previous checker whose joints and
gravity are the same (``keeps_limits``), so a change of the grid or the warning threshold
is quick.
"""

from __future__ import annotations

from dataclasses import dataclass

from irb140_dynamics.core.model.robot_model import RobotModel

from .check import TrajectoryReport, check_trajectory
from .limits import Limits, torque_limit_notes, trajectory_limits
from .message import Trajectory
from .retiming import retime

OK, WARN, ERROR = "ok", "warn", "error"


@dataclass(frozen=True, eq=False)
class TrajectoryChecker:
    """``model`` and its ``limits`` (``notes``: where the torque limits come from); ``grid``:
    about how many steps a re-timing takes over the path; ``warn_use``: a trajectory using
    more of a limit than this [%] is a warning."""

    model: RobotModel
    limits: Limits
    notes: tuple[str, ...]
    grid: int
    warn_use: float

    @classmethod
    def of(cls, model: RobotModel, grid: int, warn_use: float, previous: TrajectoryChecker | None = None):
        """The checker of ``model``; its limits derived unless ``previous`` keeps them."""
        keep = previous is not None and previous.keeps_limits(model)
        limits = previous.limits if keep else trajectory_limits(model)
        return cls(model, limits, torque_limit_notes(model, limits), grid, warn_use)

    def keeps_limits(self, model: RobotModel) -> bool:
        """Would ``model`` be held to the same limits (the same joints and gravity)?"""
        return (self.model.joints, self.model.gravity) == (model.joints, model.gravity)

    def check(self, tr: Trajectory) -> TrajectoryReport:
        return check_trajectory(self.model, tr, self.limits)

    def retime(self, tr: Trajectory) -> tuple[Trajectory, TrajectoryReport]:
        """The time-optimal trajectory of the same path, and its check (TrajectoryError if none)."""
        retimed = retime(self.model, tr, self.limits, grid=self.grid).trajectory
        return retimed, self.check(retimed)

    def level(self, report: TrajectoryReport) -> str:
        """ERROR over a limit, WARN from ``warn_use`` % of one, else OK."""
        return ERROR if not report.ok else WARN if 100 * report.worst.ratio >= self.warn_use else OK

    def figures(self, report: TrajectoryReport, notes: tuple[str, ...] = ()) -> list[tuple[str, str]]:
        """(key, value) pairs: the duration, the notes (the checker's, then ``notes``), and
        per joint and limit the peak, the limit, its use, when and in which segment."""
        pairs = [("duration [s]", f"{report.duration:.6f}")]
        pairs += [("note", note) for note in (*self.notes, *notes)]
        return pairs + [(f"{p.joint} {p.quantity}", p.line().split(": ", 1)[1]) for p in report.peaks]
