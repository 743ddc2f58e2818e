"""The path a trajectory's points lie on, as the controller interpolates them, over a grid.

The path is the controller's interpolation of the input (see ``interpolation``; the segment
before the first point is not part of it), parameterized by its length s (rad, 2-norm), so
that |q'| = 1 and the parameterization has no singular points where the input slows to
rest. Each input segment is split into steps of about equal length, so that every input point is a
grid point. At a point the path's derivatives q' and q'' are taken
from both sides (``left``, ``right``): where q' differs (a corner between linear segments,
or velocities that change length or direction), no timing can pass without stopping, so the
grid point is a stop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .interpolation import spline
from .message import Trajectory, TrajectoryError

MIN_STEPS = 4  # grid steps per input segment at least
REST_STEPS = 64  # and next to a point at rest on a curve


@dataclass(frozen=True, eq=False)
class PathGrid:
    """s (G+1,), q (G+1, n), q1 and q2 (2, G+1, n): dq/ds and d2q/ds2 from the left [0] and
    the right [1]; stops (G+1,) bool; point (G+1,) the input point each grid point starts the
    segment of (its own index at an input point); knot (G+1,) whether it is an input point."""

    s: np.ndarray
    sigma: np.ndarray  # the input's time (since its first point) at each grid point
    q: np.ndarray
    q1: np.ndarray
    q2: np.ndarray
    stops: np.ndarray
    point: np.ndarray
    knot: np.ndarray

    @property
    def delta(self) -> np.ndarray:
        return np.diff(self.s)


def steps_per_segment(tr: Trajectory, grid: int) -> np.ndarray:
    """About ``grid`` steps in all, shared out by each segment's largest joint motion, at
    least MIN_STEPS each, REST_STEPS next to a point at rest (the path turns sharply there)."""
    motion = np.abs(np.diff(tr.q, axis=0)).max(axis=1)
    share = motion / motion.sum() if motion.sum() > 0 else np.full(len(motion), 1.0 / len(motion))
    rest = tr.has_qd & (np.abs(tr.qd).max(axis=1) == 0)  # a curve through a rest point (lines need none)
    least = np.where(rest[:-1] | rest[1:], REST_STEPS, MIN_STEPS)
    return np.maximum(least, np.ceil(grid * share).astype(int))


def path_grid(tr: Trajectory, steps: np.ndarray) -> PathGrid:
    """The grid of ``steps[k]`` steps of about equal length over input segment k; s is the
    path's length (2-norm, rad) from the first point, so |q'| = 1."""
    sp = spline(Trajectory(tr.joint_names, tr.t - tr.t[0], tr.q, tr.qd, tr.qdd, tr.has_qd, tr.has_qdd))
    seg = np.concatenate([np.full(m, k) for k, m in enumerate(steps)] + [[len(steps) - 1]])
    sigma = np.r_[_equal_lengths(sp, steps), sp.end]
    knot = np.concatenate([np.r_[True, np.zeros(m - 1, bool)] for m in steps] + [[True]])
    left_seg = np.where(knot & (np.arange(len(sigma)) > 0), np.maximum(seg - 1, 0), seg)
    left_seg[-1] = len(steps) - 1
    q = sp.evaluate(sigma, seg, order=0)[0]
    q[knot] = tr.q  # the input's points exactly, not as the polynomials round them
    q1r, q2r, rest_r = _unit_derivatives(sp, sigma, seg)
    q1l, q2l, rest_l = _unit_derivatives(sp, sigma, left_seg)
    rest = rest_r | rest_l
    q1, q2 = np.stack([q1l, q1r]), np.stack([q2l, q2r])
    stops = np.linalg.norm(q1l - q1r, axis=1) > 1e-9
    stops[0] = stops[-1] = True
    stops |= rest
    s = np.r_[0.0, np.cumsum(_lengths(sp, sigma, seg))]
    if not (np.diff(s) > 0).all():
        i = int(np.flatnonzero(np.diff(s) <= 0)[0])
        raise TrajectoryError(
            f"point {seg[i]}: the path does not move between points {seg[i]} and {seg[i] + 1} "
            "(a pause: split the trajectory there)"
        )
    point = np.r_[seg[:-1], len(steps)]
    return PathGrid(s, sigma, q, q1, q2, stops, point, knot)


def _equal_lengths(sp, steps, fine: int = 4) -> np.ndarray:
    """Input times splitting each segment k into steps[k] steps of about equal path length
    (the first steps[k] of the steps[k] + 1 ends of each, all segments in a row)."""
    m = np.asarray(steps)
    count = fine * m + 1
    seg = np.repeat(np.arange(len(m)), count)
    first = np.repeat(np.r_[0, np.cumsum(count)[:-1]], count)
    tau = (np.arange(len(seg)) - first) / (fine * m[seg]) * sp.T[seg]
    _, v = sp.evaluate(sp.t0[seg] + tau, seg, order=1)
    speed = np.linalg.norm(v, axis=1)
    out = []
    for k, (a, b) in enumerate(zip(first[np.r_[0, np.cumsum(count)[:-1]]], np.cumsum(count))):
        t, f = tau[a:b], speed[a:b]
        length = np.r_[0.0, np.cumsum((f[1:] + f[:-1]) / 2 * np.diff(t))]
        targets = np.linspace(0.0, length[-1], m[k] + 1)[:-1]
        out.append(sp.t0[k] + (np.interp(targets, length, t) if length[-1] > 0 else t[::fine][:-1]))
    return np.concatenate(out)


def _unit_derivatives(sp, sigma, seg):
    """dq/ds and d2q/ds2 by path length from the input's time derivatives, and where the
    input stands still (|dq/dsigma| = 0): there dq/ds is taken a little inside the segment,
    d2q/ds2 is 0 and the grid point is a stop (the curvature is unbounded)."""
    _, v, a = sp.evaluate(sigma, seg)
    speed = np.linalg.norm(v, axis=1)
    still = speed <= 1e-9 * (1.0 + speed.max())
    if still.any():
        eps = 1e-3 * sp.T[seg[still]]
        inside = np.clip(sigma[still], sp.t0[seg[still]] + eps, sp.t0[seg[still]] + sp.T[seg[still]] - eps)
        _, v[still], a[still] = sp.evaluate(inside, seg[still])
        speed[still] = np.linalg.norm(v[still], axis=1)
    speed = np.maximum(speed, 1e-300)[:, None]
    q1 = v / speed
    q2 = (a - (q1 * a).sum(axis=1, keepdims=True) * q1) / speed**2
    q2[still] = 0.0  # the path's curvature grows without bound there; it is passed at rest (x = 0)
    return q1, q2, still


def _lengths(sp, sigma, seg) -> np.ndarray:
    """Path length of each grid step (Gauss-Legendre, 3 nodes, on the step's segment)."""
    nodes, weights = np.polynomial.legendre.leggauss(3)
    h = np.diff(sigma)
    s0 = seg[:-1]
    total = np.zeros(len(h))
    for x, w in zip(nodes, weights):
        _, v = sp.evaluate(sigma[:-1] + (x + 1) / 2 * h, s0, order=1)
        total += w / 2 * h * np.linalg.norm(v, axis=1)
    return total
