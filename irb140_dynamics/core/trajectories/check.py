"""Per joint, the peak torque, velocity and acceleration of a trajectory as the controller
plays it, against the limits, with the time and the point of the worst sample.

Torque is ``rnea`` of the model (payload, armature and friction included) along the
controller's interpolation (see ``interpolation``). Sampling: every segment at
``PER_SEGMENT`` intervals or more and none longer than ``MAX_STEP`` (the period of a 1 kHz
controller, which only ever evaluates the interpolation at its update instants); then each
joint's worst sample of each quantity is refined to the local maximum between its
neighbours (the vertex of the parabola through the three samples, evaluated), so the
peak reported is the interpolation's, not a sample's.
``miss`` bounds what could hide between two samples elsewhere: |second difference| / 8
(a function with |f''| <= K exceeds the larger of two samples h apart by at most K h^2/8).
A velocity that steps at a point (linear interpolation) needs an unbounded acceleration:
reported as inf at that point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.dynamics import rnea_batch
from irb140_dynamics.core.model.robot_model import RobotModel

from .interpolation import Spline, sample_times, spline
from .limits import Limits, trajectory_limits
from .message import Trajectory

PER_SEGMENT = 32
MAX_STEP = 1e-3  # s
QUANTITIES = ("torque", "velocity", "acceleration")
UNITS = {"torque": "N m", "velocity": "rad/s", "acceleration": "rad/s^2"}


@dataclass(frozen=True)
class JointPeak:
    """The largest |value| of one quantity at one joint: signed value, limit (inf: none),
    value / limit, when (s from start), the point the segment starts at (-1: before the
    first point) and ``miss``, the bound on a larger value hidden between samples."""

    joint: str
    quantity: str
    value: float
    limit: float
    time: float
    point: int
    miss: float = 0.0

    @property
    def ratio(self) -> float:
        return abs(self.value) / self.limit if self.limit > 0 else np.inf

    @property
    def ok(self) -> bool:
        return self.ratio <= 1.0

    def line(self) -> str:
        where = "before point 0" if self.point < 0 else f"segment from point {self.point}"
        of = f"of {self.limit:.4g} ({100 * self.ratio:.1f} %)" if np.isfinite(self.limit) else "(no limit)"
        return f"{self.joint} {self.quantity}: {self.value:+.4g} {UNITS[self.quantity]} {of} at t = {self.time:.4f} s, {where}"


@dataclass(frozen=True, eq=False)
class TrajectoryReport:
    peaks: tuple[JointPeak, ...]  # joint by joint, torque, velocity, acceleration
    duration: float
    samples: int
    torque_source: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return all(p.ok for p in self.peaks)

    @property
    def worst(self) -> JointPeak:
        return max(self.peaks, key=lambda p: p.ratio)

    def lines(self) -> list[str]:
        return [p.line() for p in self.peaks]

    def headline(self) -> str:
        """The report in one line: its duration, the verdict and the worst use of a limit."""
        verdict = "within every limit" if self.ok else "OVER A LIMIT"
        return f"{self.duration:.3f} s, {verdict}; worst: {self.worst.line()}"


def profiles(model: RobotModel, sp: Spline, t, seg) -> dict[str, np.ndarray]:
    """Torque, velocity and acceleration (each (len(t), n)) of the interpolation at t."""
    q, qd, qdd = sp.evaluate(t, seg)
    return {"torque": rnea_batch(model, q, qd, qdd), "velocity": qd, "acceleration": qdd}


def check_trajectory(
    model: RobotModel,
    tr: Trajectory,
    limits: Limits | None = None,
    start=None,
    per_segment: int = PER_SEGMENT,
    max_step: float = MAX_STEP,
) -> TrajectoryReport:
    """The report of ``tr`` played by the controller on ``model`` (its payload included)."""
    limits = trajectory_limits(model) if limits is None else limits
    sp = spline(tr, start)
    t, seg = sample_times(sp, per_segment, max_step)
    values = profiles(model, sp, t, seg)
    peaks = []
    for j, name in enumerate(model.joint_names):
        for quantity in QUANTITIES:
            limit = getattr(limits, quantity)[j]
            peaks.append(_peak(model, sp, t, seg, values[quantity][:, j], quantity, j, name, limit))
    jumps = _velocity_steps(sp)
    if jumps is not None:
        k, j = jumps
        i = 3 * j + 2
        peaks[i] = JointPeak(
            model.joint_names[j], "acceleration", np.inf, limits.acceleration[j], float(sp.t0[k]), int(sp.point[k])
        )
    return TrajectoryReport(tuple(peaks), sp.end, len(t), limits.torque_source)


def _peak(model, sp, t, seg, f, quantity, j, name, limit) -> JointPeak:
    i = int(np.argmax(np.abs(f)))
    miss = float(np.abs(np.diff(f, 2)).max() / 8) if len(f) > 2 else 0.0
    value, when = float(f[i]), float(t[i])
    if 0 < i < len(t) - 1 and seg[i - 1] == seg[i + 1]:  # refine: the parabola through the three samples
        (t0, t1, t2), (f0, f1, f2) = t[i - 1 : i + 2], np.abs(f[i - 1 : i + 2])
        denom = (t0 - t1) * (t0 - t2) * (t1 - t2)
        a = (t2 * (f1 - f0) + t1 * (f0 - f2) + t0 * (f2 - f1)) / denom if denom else 0.0
        b = (t2**2 * (f0 - f1) + t1**2 * (f2 - f0) + t0**2 * (f1 - f2)) / denom if denom else 0.0
        if a < 0:
            vertex = float(np.clip(-b / (2 * a), t0, t2))
            refined = float(profiles(model, sp, np.array([vertex]), np.array([seg[i]]))[quantity][0, j])
            if abs(refined) > abs(value):
                value, when = refined, vertex
    return JointPeak(name, quantity, value, float(limit), when, int(sp.point[seg[i]]), miss)


def _velocity_steps(sp: Spline):
    """(segment, joint) where the velocity steps most at a point, if anywhere."""
    if len(sp.T) < 2:
        return None
    k = np.arange(1, len(sp.T))
    left = sp.evaluate(sp.t0[k], k - 1, order=1)[1]
    right = sp.evaluate(sp.t0[k], k, order=1)[1]
    step = np.abs(right - left)
    if step.max() <= 1e-9 * (1.0 + np.abs(left).max()):
        return None
    s, j = np.unravel_index(np.argmax(step), step.shape)
    return int(k[s]), int(j)
