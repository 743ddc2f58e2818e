"""The worst static torques over the joint ranges: sample poses, then exact coordinate
ascent from the best samples.

Units: rad, N m. A static torque (gravity, or any sum of gravity torques) depends on each
joint angle q_k, the others fixed, exactly as

    tau_j(q_k) = A + B cos(q_k) + C sin(q_k),

since every term is linear in joint k's rotation. Three evaluations give A, B, C, and the
maximum of A + R cos(q_k - phi) over [lower_k, upper_k] is known in closed form. Coordinate
ascent with this exact 1-D maximum runs for many starts and many objectives at once (each
objective a weighted sum w . tau, e.g. +tau_j or -tau_j) until a sweep gains less than
1e-12 of the torque scale, or the analysis is out of time or cancelled (see ``stop``: checked
at each step; the poses reached so far are real, their torques lower bounds of the maxima).
The samples are quasi-random poses plus the right-angle poses, where maxima often lie; of
equal maxima the simplest pose is returned.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.payload.stop import out_of_time

StaticTorque = Callable[[np.ndarray], np.ndarray]  # Q (N, n) -> tau (N, n)

_THIRDS = np.array([0.0, 2 * math.pi / 3, 4 * math.pi / 3])
GRID = 65  # points of a gridded coordinate's step (a mimic joint's torques are no single harmonic of it)


def quasi_random(count: int, dim: int) -> np.ndarray:
    """``count`` points evenly spread over the unit cube [0, 1)^dim (Kronecker R-sequence)."""
    phi = 2.0
    for _ in range(50):  # the root of x^(dim+1) = x + 1
        phi = (1.0 + phi) ** (1.0 / (dim + 1))
    alpha = phi ** -np.arange(1.0, dim + 1)
    return (0.5 + np.arange(1, count + 1)[:, None] * alpha) % 1.0


def right_angle_poses(lower, upper, max_count: int = 4096, sliding=None) -> np.ndarray:
    """All poses with every angle a multiple of 90 deg in (-180, 180] within [lower, upper]
    and every prismatic joint (``sliding``) at an end of its range (none if more than
    ``max_count``): the simple poses where maxima often lie."""
    quarter = math.pi / 2
    first = [math.ceil(max(lo, -math.pi + 1e-9) / quarter) for lo in lower]
    last = [math.floor(min(up, math.pi) / quarter) for up in upper]
    angles = [quarter * np.arange(a, b + 1) for a, b in zip(first, last)]
    for k in np.flatnonzero(np.zeros(len(angles), bool) if sliding is None else sliding):
        angles[k] = np.unique([lower[k], upper[k]])
    if math.prod(len(a) for a in angles) > max_count:
        return np.empty((0, len(angles)))
    return np.stack(np.meshgrid(*angles, indexing="ij"), axis=-1).reshape(-1, len(angles))


def harmonic_argmax(A, B, C, lower: float, upper: float):
    """argmax of A + B cos(x) + C sin(x) over x in [lower, upper], and the maximum."""
    R, phi = np.hypot(B, C), np.arctan2(C, B)
    peak = phi + 2 * math.pi * np.ceil((lower - phi) / (2 * math.pi))  # first peak >= lower
    edge = np.where(np.cos(lower - phi) >= np.cos(upper - phi), lower, upper)
    x = np.where(peak <= upper, peak, edge)
    return x, A + R * np.cos(x - phi)


@dataclass(frozen=True, eq=False)
class JointRanges:
    """The box of joint ranges [lower, upper] (rad) and a fixed set of sample poses in it."""

    lower: np.ndarray
    upper: np.ndarray
    samples: np.ndarray  # (S, n)
    sliding: np.ndarray | None = None  # (n,) the prismatic joints (their torques are affine in them)
    gridded: np.ndarray | None = None  # (n,) coordinates that mimic joints follow too: searched on a grid

    @classmethod
    def of(cls, model: RobotModel, count: int = 2048) -> JointRanges:
        """The model's joint ranges; samples: ``count`` quasi-random poses and the right angles."""
        lower, upper = np.array([j.position_limits for j in model.independent_joints]).T
        sliding = np.array([j.prismatic for j in model.independent_joints], dtype=bool)
        spread = lower + quasi_random(count, model.n) * (upper - lower)
        return cls(lower, upper, np.vstack([right_angle_poses(lower, upper, sliding=sliding), spread]), sliding)

    def maximize(
        self,
        torque: StaticTorque,
        weights: np.ndarray,
        sample_torques: np.ndarray | None = None,
        warm: np.ndarray | None = None,
        starts: int = 4,
        rtol: float = 1e-12,
    ) -> tuple[np.ndarray, np.ndarray]:
        """max over the box of weights[k] . torque(q) for each row k: (values (K,), poses (K, n)).

        Starts from the ``starts`` best samples of each objective (``sample_torques`` =
        torque(samples) may be passed to reuse it) and from ``warm`` (K, n) if given.
        """
        W = np.atleast_2d(np.asarray(weights, dtype=float))
        K, n = W.shape
        if sample_torques is None:
            sample_torques = torque(self.samples)
        best = np.argpartition(-(sample_torques @ W.T), starts - 1, axis=0)[:starts]  # (starts, K)
        X = self.samples[best]  # (starts, K, n)
        if warm is not None:
            X = np.concatenate([X, np.asarray(warm, dtype=float)[None]])
        tol = rtol * max(1.0, float(np.max(np.abs(sample_torques))))
        X, F = self._ascend(torque, W, X, tol)
        simplest = np.where(F.max(axis=0) - tol <= F, np.sum(_wrapped(X) ** 2, axis=-1), np.inf)
        poses = X[np.argmin(simplest, axis=0), np.arange(K)]  # of equal maxima the nearest q = 0
        return self._canonical(torque, W, poses, tol)

    def climb(self, torque: StaticTorque, weights: np.ndarray, starts: np.ndarray, rtol: float = 1e-12):
        """Coordinate ascent of objective weights[k] . torque from starts[k] (K, n): (values
        (K,), poses (K, n)), the poses made simple as in ``maximize``."""
        W, X = np.atleast_2d(weights), np.asarray(starts, dtype=float)[None]
        tol = rtol * max(1.0, float(np.max(np.abs(torque(X[0])))))
        X, _ = self._ascend(torque, W, X, tol)
        return self._canonical(torque, W, X[0], tol)

    def _values(self, torque: StaticTorque, W: np.ndarray, X: np.ndarray) -> np.ndarray:
        """Objective k at each pose X[..., k, :]."""
        tau = torque(X.reshape(-1, X.shape[-1])).reshape(X.shape)
        return np.einsum("...kn,kn->...k", tau, W)

    def _ascend(self, torque, W, X, tol, max_sweeps: int = 1000):
        """Coordinate ascent from every start X[s, k] (for objective k), each step exact.

        Near a maximum the sweeps' steps shrink geometrically, by lam each; where that
        holds, the step to the limit, step * lam / (1 - lam), is tried too (Aitken). The
        poses a sweep's first step needs are evaluated with that trial, for both outcomes:
        one call of the torques fewer per sweep (the same numbers: each pose's torques are
        its own).
        """
        X = X.copy()
        moving = np.flatnonzero(self.lower < self.upper)  # (a coordinate held has no step)
        first = moving[0] if moving.size and not self._special(moving[0]) else None
        ahead = None if first is None else self._values(torque, W, _thirds(X, first))  # the first step's values
        F = self._values(torque, W, X) if ahead is None else ahead[0]
        step = np.zeros_like(X)
        for _ in range(max_sweeps):
            before, X_before = F, X.copy()
            for k in moving:
                if out_of_time():
                    return X, self._values(torque, W, X)
                X, F = self._coordinate_step(torque, W, X, k, tol, ahead if k == first else None)
            step, last = X - X_before, step
            lam = np.sum(step * last, axis=-1) / np.maximum(np.sum(last * last, axis=-1), 1e-300)
            jump = np.clip(lam, 0.0, 0.95) / (1 - np.clip(lam, 0.0, 0.95))
            trial = np.clip(X + jump[..., None] * step, self.lower, self.upper)
            if first is None:
                f = self._values(torque, W, trial)
            else:  # (both outcomes' first step: 3 poses each, the first the pose itself)
                both = self._values(torque, W, np.concatenate([_thirds(X, first), _thirds(trial, first)]))
                f = both[3]
            better = f > F + 0.01 * tol
            X, F = np.where(better[..., None], trial, X), np.where(better, f, F)
            if first is not None:
                ahead = np.where(better, both[3:], both[:3])
            if np.all(F - before <= tol):
                break
        return X, (self._values(torque, W, X) if ahead is None else ahead[0])

    def _special(self, k) -> bool:
        """Is coordinate k searched otherwise than by its exact harmonic maximum?"""
        return bool((self.gridded is not None and self.gridded[k]) or (self.sliding is not None and self.sliding[k]))

    def _coordinate_step(self, torque, W, X, k, tol, f=None):
        """Each X[s, k] moved to the exact maximum along angle k (a prismatic joint: the
        better end of its range, static torques being affine in it): (X, values). ``f``:
        the values at ``_thirds(X, k)``, if known."""
        if self.gridded is not None and self.gridded[k]:  # a grid, then a finer one about its best
            step = (self.upper[k] - self.lower[k]) / (GRID - 1)
            X, F = self._best_of(torque, W, X, k, tol, np.linspace(self.lower[k], self.upper[k], GRID))
            finer = X[..., k][None] + np.linspace(-step, step, GRID).reshape((-1,) + (1,) * (X.ndim - 1))
            return self._best_of(torque, W, X, k, tol, np.clip(finer, self.lower[k], self.upper[k]))
        if self.sliding is not None and self.sliding[k]:
            return self._best_of(torque, W, X, k, tol, np.array([self.lower[k], self.upper[k]]))
        trial = _thirds(X, k)
        f = self._values(torque, W, trial) if f is None else f  # (3, S, K), f[0] at X
        theta = trial[..., k]
        A = f.mean(axis=0)
        B = 2 / 3 * np.sum(f * np.cos(theta), axis=0)
        C = 2 / 3 * np.sum(f * np.sin(theta), axis=0)
        x, top = harmonic_argmax(A, B, C, self.lower[k], self.upper[k])
        better = top > f[0] + 0.01 * tol  # not for rounding noise
        X = X.copy()
        X[..., k] = np.where(better, x, X[..., k])
        return X, np.where(better, top, f[0])

    def _best_of(self, torque, W, X, k, tol, values):
        """Each X[s, k] moved to the best of ``values`` (G,) or (G, ...) if better: (X, values)."""
        trial = np.repeat(X[None], 1 + len(values), axis=0)
        trial[1:, ..., k] = values.reshape((len(values),) + (1,) * (X.ndim - 1)) if values.ndim == 1 else values
        f = self._values(torque, W, trial)
        best = np.argmax(f, axis=0)
        top = np.take_along_axis(f, best[None], axis=0)[0]
        better = top > f[0] + 0.01 * tol
        X = X.copy()
        X[..., k] = np.where(better, np.take_along_axis(trial[..., k], best[None], axis=0)[0], X[..., k])
        return X, np.where(better, top, f[0])

    def _canonical(self, torque, W, poses, tol):
        """The same maxima (to ``tol``) in simpler poses: each angle, where the value stays,
        wrapped nearest 0, then 0, then 0 with the next joint turning by it instead."""
        best = self._values(torque, W, poses)
        for k in range(poses.shape[-1]):
            if out_of_time():
                break
            for simpler in (_wrapped, _zeroed, _handed_on):
                trial = np.clip(simpler(poses, k), self.lower, self.upper)
                keep = self._values(torque, W, trial) >= best - tol
                poses = np.where(keep[:, None], trial, poses)
        return self._values(torque, W, poses), poses


def _thirds(X, k):
    """X three times, angle k turned by 0, 2 pi / 3 and 4 pi / 3: (3, ...) poses."""
    trial = np.repeat(X[None], 3, axis=0)
    trial[..., k] += _THIRDS.reshape((3,) + (1,) * (X.ndim - 1))
    return trial


def _wrapped(Q, k=slice(None)):
    """Q with angle k (default: all) wrapped into [-pi, pi]."""
    Q = Q.copy()
    Q[..., k] -= 2 * math.pi * np.round(Q[..., k] / (2 * math.pi))
    return Q


def _zeroed(Q, k):
    Q = Q.copy()
    Q[:, k] = 0.0
    return Q


def _handed_on(Q, k):
    """q_k = 0 and q_(k+1) + q_k: the same pose beyond joint k+1 if the two axes are parallel."""
    handed = _zeroed(Q, k)
    if k + 1 < Q.shape[1]:
        handed[:, k + 1] += Q[:, k]
    return handed
