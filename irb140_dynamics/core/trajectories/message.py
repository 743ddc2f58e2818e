"""A JointTrajectory as the core sees it, read from and written to the mapping that
``ros2 topic echo`` prints (header, joint_names, points with positions, velocities,
accelerations, effort and time_from_start {sec, nanosec}).

Joints come in any order and are matched to the model's by name. Per point, velocities and
accelerations are optional (the controller then interpolates with a lower degree). Bad
input raises TrajectoryError, one line naming the point and the reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.io.stamps import NANOSECONDS_PER_SECOND, sec_nanosec, seconds


class TrajectoryError(ValueError):
    """A trajectory that cannot be checked or re-timed, in one line."""


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Points in the model's joint order: t (N,) s from start, strictly increasing; q, qd,
    qdd (N, n) rad, rad/s, rad/s^2; has_qd, has_qdd (N,) whether a point carries them (a
    row without is zeros)."""

    joint_names: tuple[str, ...]
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    has_qd: np.ndarray
    has_qdd: np.ndarray

    def __post_init__(self):
        _check_arrays(self)

    @property
    def n(self) -> int:
        return len(self.joint_names)

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    @classmethod
    def of(cls, joint_names, t, q, qd=None, qdd=None) -> Trajectory:
        """From arrays: qd, qdd None (no point carries them) or (N, n)."""
        q = np.array(q, dtype=float)
        N = len(q)
        has_qd, has_qdd = np.full(N, qd is not None), np.full(N, qdd is not None)
        qd = np.zeros_like(q) if qd is None else np.array(qd, dtype=float)
        qdd = np.zeros_like(q) if qdd is None else np.array(qdd, dtype=float)
        return cls(tuple(joint_names), np.array(t, dtype=float), q, qd, qdd, has_qd, has_qdd)

    @classmethod
    def from_message(cls, message, joint_names) -> Trajectory:
        """From the ``ros2 topic echo`` mapping, reordered to ``joint_names`` (the model's)."""
        if not isinstance(message, dict):
            raise TrajectoryError("not a JointTrajectory: expected a mapping with joint_names and points")
        names = message.get("joint_names")
        if not isinstance(names, list) or not all(isinstance(x, str) for x in names):
            raise TrajectoryError("joint_names: must be a list of joint names")
        order = joint_indices(names, joint_names)
        points = message.get("points")
        if not isinstance(points, list) or len(points) < 2:
            raise TrajectoryError("points: need at least 2 points")
        t, q, qd, qdd, has_qd, has_qdd = [], [], [], [], [], []
        for k, point in enumerate(points):
            if not isinstance(point, dict):
                raise TrajectoryError(f"point {k}: not a mapping")
            t.append(_time(point.get("time_from_start"), k))
            q.append(_values(point, "positions", k, names, required=True)[order])
            for field, rows, flags in (("velocities", qd, has_qd), ("accelerations", qdd, has_qdd)):
                values = _values(point, field, k, names, required=False)
                flags.append(values is not None)
                rows.append(np.zeros(len(order)) if values is None else values[order])
            if has_qdd[-1] and not has_qd[-1]:
                raise TrajectoryError(
                    f"point {k}: accelerations without velocities (the controller would not interpolate this segment)"
                )
        return cls(
            tuple(joint_names),
            np.array(t),
            np.array(q),
            np.array(qd),
            np.array(qdd),
            np.array(has_qd),
            np.array(has_qdd),
        )

    def to_message(self, frame_id: str = "") -> dict:
        """The ``ros2 topic echo`` mapping: positions, velocities and accelerations where given."""
        points = []
        for k in range(len(self.t)):
            sec, nanosec = sec_nanosec(self.t[k])
            point = {
                "positions": self.q[k].tolist(),
                "velocities": self.qd[k].tolist() if self.has_qd[k] else [],
                "accelerations": self.qdd[k].tolist() if self.has_qdd[k] else [],
                "effort": [],
                "time_from_start": {"sec": sec, "nanosec": nanosec},
            }
            points.append(point)
        return {
            "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": frame_id},
            "joint_names": list(self.joint_names),
            "points": points,
        }


def joint_indices(names, model_names) -> np.ndarray:
    """For each model joint, its index in ``names``; unknown, duplicate or missing joints refused."""
    if len(set(names)) != len(names):
        raise TrajectoryError(f"joint_names: duplicates in {names}")
    unknown = [x for x in names if x not in model_names]
    if unknown:
        raise TrajectoryError(
            f"joint_names: unknown joint(s) {', '.join(unknown)} (the model has {', '.join(model_names)})"
        )
    missing = [x for x in model_names if x not in names]
    if missing:
        raise TrajectoryError(f"joint_names: no {', '.join(missing)} (every joint of the model must move or hold)")
    return np.array([names.index(x) for x in model_names])


def _time(value, k: int) -> float:
    if not isinstance(value, dict) or not {"sec", "nanosec"} <= value.keys():
        raise TrajectoryError(f"point {k}: time_from_start must be {{sec, nanosec}}")
    sec, nanosec = value["sec"], value["nanosec"]
    if (
        not all(isinstance(x, int) and not isinstance(x, bool) for x in (sec, nanosec))
        or not 0 <= nanosec < NANOSECONDS_PER_SECOND
    ):
        raise TrajectoryError(f"point {k}: time_from_start {{sec: {sec}, nanosec: {nanosec}}} is not a duration")
    return seconds(sec, nanosec)


def _values(point: dict, field: str, k: int, names: list, required: bool) -> np.ndarray | None:
    values = point.get(field)
    if values is None or (isinstance(values, list) and not values):
        if required:
            raise TrajectoryError(f"point {k}: no {field}")
        return None
    if not isinstance(values, list) or len(values) != len(names):
        raise TrajectoryError(f"point {k}: {field} must be {len(names)} numbers, one per joint name")
    for name, x in zip(names, values):
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
            raise TrajectoryError(f"point {k}: {field} of {name} is {x!r}, not a finite number")
    return np.array(values, dtype=float)


def _check_arrays(tr: Trajectory) -> None:
    N, n = len(tr.t), len(tr.joint_names)
    if N < 2:
        raise TrajectoryError("points: need at least 2 points")
    for name in ("q", "qd", "qdd"):
        a = getattr(tr, name)
        if a.shape != (N, n):
            raise TrajectoryError(f"{name}: shape {a.shape}, expected ({N}, {n})")
        bad = np.argwhere(~np.isfinite(a))
        if len(bad):
            k, j = bad[0]
            raise TrajectoryError(f"point {k}: {name} of {tr.joint_names[j]} is {a[k, j]}, not a finite number")
    if not np.isfinite(tr.t).all() or tr.t[0] < 0:
        raise TrajectoryError("time_from_start: must be finite and >= 0")
    steps = np.flatnonzero(np.diff(tr.t) <= 0)
    if len(steps):
        k = steps[0] + 1
        raise TrajectoryError(
            f"point {k}: time_from_start {tr.t[k]:.9g} s is not after point {k - 1}'s "
            f"{tr.t[k - 1]:.9g} s (times must increase strictly)"
        )
    if (tr.has_qdd & ~tr.has_qd).any():
        k = int(np.flatnonzero(tr.has_qdd & ~tr.has_qd)[0])
        raise TrajectoryError(f"point {k}: accelerations without velocities")
