"""A trajectory sampled exactly as ros2_control's joint_trajectory_controller interpolates it.

The controller (joint_trajectory_controller/src/trajectory.cpp, ``interpolate_between_points``)
joins two consecutive points by a polynomial in the time since the first of them, per joint:

- quintic when both points carry velocities and accelerations (positions, velocities and
  accelerations matched at both ends),
- cubic when both carry velocities (positions and velocities matched; the acceleration
  it outputs is the cubic's),
- linear otherwise (constant velocity, acceleration 0: the velocity steps at the points).

Before the first point's time_from_start it interpolates the same way from the state it
held when the trajectory arrived (velocities and accelerations zero-filled when the first
point has them, ``set_point_before_trajectory_msg``); here that state is ``start`` (by
default at rest at the first point's positions). After the last point it holds the last
point. The coefficients below are the controller's, term for term.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .message import Trajectory


@dataclass(frozen=True, eq=False)
class Spline:
    """Segments s = 0..S-1: start time t0 (S,), duration T (S,), polynomial coefficients c
    (S, 6, n) in the time since t0 (c[s, k] multiplies tau^k), ``point`` (S,) the index of
    each segment's first point (-1: the segment before the first point) and ``degree`` (S,)."""

    t0: np.ndarray
    T: np.ndarray
    c: np.ndarray
    point: np.ndarray
    degree: np.ndarray

    @property
    def end(self) -> float:
        return float(self.t0[-1] + self.T[-1])

    def segment_of(self, t: np.ndarray) -> np.ndarray:
        """The segment each time falls in (the controller's [t0, t1); the end in the last)."""
        return np.clip(np.searchsorted(self.t0, t, side="right") - 1, 0, len(self.t0) - 1)

    def evaluate(self, t, segment=None, order: int = 2) -> tuple[np.ndarray, ...]:
        """q, qd, qdd (each (len(t), n)) at times t; derivatives up to ``order``."""
        t = np.asarray(t, dtype=float)
        seg = self.segment_of(t) if segment is None else np.asarray(segment)
        tau = np.clip(t - self.t0[seg], 0.0, self.T[seg])
        top = int(self.degree.max())
        c = self.c[seg, : top + 1]
        tau = tau[:, None]
        out = []
        for d in range(order + 1):  # Horner on the d-th derivative
            if d > top:
                out.append(np.zeros((len(t), c.shape[2])))
                continue
            value = c[:, top] * _FALLING[d, top]
            for k in range(top - 1, d - 1, -1):
                value = value * tau + c[:, k] * _FALLING[d, k]
            out.append(value)
        return tuple(out)


_FALLING = np.array([[np.prod(np.arange(k - d + 1, k + 1)) for k in range(6)] for d in range(3)], dtype=float)


def spline(tr: Trajectory, start=None) -> Spline:
    """The controller's interpolation of ``tr``; ``start`` = (q, qd, qdd) held at time 0
    (default at rest at the first point); a segment before the first point only if its
    time_from_start is > 0."""
    t, q, qd, qdd = tr.t, tr.q, tr.qd * tr.has_qd[:, None], tr.qdd * tr.has_qdd[:, None]
    has_qd, has_qdd, first = tr.has_qd, tr.has_qdd, np.arange(len(t))
    if t[0] > 0:
        q0, qd0, qdd0 = (q[0], np.zeros(tr.n), np.zeros(tr.n)) if start is None else map(np.asarray, start)
        t, q = np.r_[0.0, t], np.vstack([q0, q])
        qd, qdd = np.vstack([qd0, qd]), np.vstack([qdd0, qdd])
        has_qd, has_qdd, first = np.r_[has_qd[0], has_qd], np.r_[has_qdd[0], has_qdd], np.r_[-1, first]
    T = np.diff(t)
    vel = has_qd[:-1] & has_qd[1:]
    acc = vel & has_qdd[:-1] & has_qdd[1:]
    c = np.zeros((len(T), 6, tr.n))
    p0, p1, v0, v1, a0, a1 = q[:-1], q[1:], qd[:-1], qd[1:], qdd[:-1], qdd[1:]
    T1, T2, T3, T4, T5 = (T[:, None] ** k for k in range(1, 6))
    linear = ~vel
    c[:, 0] = p0
    c[linear, 1] = ((p1 - p0) / T1)[linear]
    cubic = vel & ~acc
    c[cubic, 1] = v0[cubic]
    c[cubic, 2] = ((-3.0 * p0 + 3.0 * p1 - 2.0 * v0 * T1 - v1 * T1) / T2)[cubic]
    c[cubic, 3] = ((2.0 * p0 - 2.0 * p1 + v0 * T1 + v1 * T1) / T3)[cubic]
    c[acc, 1], c[acc, 2] = v0[acc], 0.5 * a0[acc]
    c[acc, 3] = ((-20.0 * p0 + 20.0 * p1 - 3.0 * a0 * T2 + a1 * T2 - 12.0 * v0 * T1 - 8.0 * v1 * T1) / (2.0 * T3))[acc]
    c[acc, 4] = (
        (30.0 * p0 - 30.0 * p1 + 3.0 * a0 * T2 - 2.0 * a1 * T2 + 16.0 * v0 * T1 + 14.0 * v1 * T1) / (2.0 * T4)
    )[acc]
    c[acc, 5] = ((-12.0 * p0 + 12.0 * p1 - a0 * T2 + a1 * T2 - 6.0 * v0 * T1 - 6.0 * v1 * T1) / (2.0 * T5))[acc]
    degree = np.where(acc, 5, np.where(vel, 3, 1))
    return Spline(t[:-1], T, c, first[:-1], degree)


def sample_times(sp: Spline, per_segment: int, max_step: float | None = None, segments=None):
    """Times (and their segments) covering every segment (or those in ``segments``) evenly,
    ends included: at least ``per_segment`` intervals per segment and none longer than
    ``max_step`` [s]."""
    index = np.arange(len(sp.T)) if segments is None else np.asarray(segments, dtype=int)
    m = np.full(len(index), per_segment)
    if max_step:
        m = np.maximum(m, np.ceil(sp.T[index] / max_step).astype(int))
    which = np.repeat(np.arange(len(index)), m + 1)
    first = np.repeat(np.r_[0, np.cumsum(m + 1)[:-1]], m + 1)
    frac = (np.arange(len(which)) - first) / m[which]
    seg = index[which]
    return sp.t0[seg] + frac * sp.T[seg], seg
