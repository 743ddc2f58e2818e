"""Excitation trajectories: periodic joint motions that make the base parameters observable.

Each joint follows a finite Fourier series (Swevers, Ganseman, Tukel, De Schutter, Van
Brussel 1997) of base frequency w = 2 pi / period and K harmonics:

    q_j(t)   = q0_j + sum_l  a_jl / (w l) sin(w l t) - b_jl / (w l) cos(w l t)
    qd_j(t)  =        sum_l  a_jl cos(w l t) + b_jl sin(w l t)
    qdd_j(t) =        sum_l  w l (-a_jl sin(w l t) + b_jl cos(w l t))

It is periodic, so it can be repeated and averaged. It starts (and ends each period) at
rest: sum_l a_jl = 0 and sum_l l b_jl = 0, so a controller can start it from q(0) held
still. The optimiser picks the coefficients of harmonics 2..K freely; those of harmonic 1
follow from the rest conditions. Each joint's motion is then scaled as large as its limits
allow (within ``margin`` of the position range, 98 % of the velocity and acceleration
limits), and q0 centres it in the range. The cost is log cond(Y_b): the condition number
of the base regressor stacked over ``samples`` states of one period (Y_b's columns as they
are, in SI units), minimised by SciPy's L-BFGS-B from a seeded random start. The optimum
is then scaled down where its torques (rnea, the payload included) exceed 98 % of a
joint's torque limit (see ``torque_limits``).

The joints are the model's independent ones (``joint_names``): a mimic joint moves with the
joint it follows, and its limits bound that joint's motion (``Limits.of``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from irb140_dynamics.core.dynamics import rnea_batch
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.regressor import regressor_batch
from irb140_dynamics.identification.base import BaseParameters, find_base_parameters
from irb140_dynamics.identification.torque_limits import TorqueScaling, holding_pose, within_torque_limits

DEFAULT_PERIOD = 10.0  # s
DEFAULT_HARMONICS = 5
DEFAULT_MARGIN = 0.05  # of each joint's position range, kept free at both ends
DEFAULT_SPEED = 1.0  # rad/s where a joint gives no velocity limit
DEFAULT_ACCELERATION = 5.0  # rad/s^2 where a joint gives no acceleration limit
CHECK_POINTS_PER_HARMONIC = 100  # limit checks: points per period of the highest harmonic
HEADROOM = 0.98  # of the velocity, acceleration and torque limits: peaks between check points stay within


@dataclass(frozen=True, eq=False)
class FourierTrajectory:
    """q(t) of every joint as a finite Fourier series (see the module's docstring)."""

    period: float  # s
    q0: np.ndarray  # (n,) rad
    a: np.ndarray  # (n, K) rad/s
    b: np.ndarray  # (n, K) rad/s

    @property
    def harmonics(self) -> int:
        return self.a.shape[1]

    def evaluate(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Q, QD, QDD), each (len(t), n), at times t [s]."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        w = 2.0 * math.pi / self.period
        l = np.arange(1, self.harmonics + 1)
        phase = w * t[:, None] * l  # (N, K)
        sin, cos = np.sin(phase), np.cos(phase)
        Q = self.q0 + (sin / (w * l)) @ self.a.T - (cos / (w * l)) @ self.b.T
        QD = cos @ self.a.T + sin @ self.b.T
        QDD = (-sin * w * l) @ self.a.T + (cos * w * l) @ self.b.T
        return Q, QD, QDD

    def times(self, rate: float, periods: int = 1) -> np.ndarray:
        """Sample times at ``rate`` Hz over ``periods`` periods, both ends included."""
        count = int(round(self.period * periods * rate))
        return np.arange(count + 1) / rate


@dataclass(frozen=True)
class Limits:
    lower: np.ndarray
    upper: np.ndarray
    speed: np.ndarray
    acceleration: np.ndarray

    @classmethod
    def of(cls, model: RobotModel, margin: float = DEFAULT_MARGIN) -> Limits:
        """The limits of the model's coordinates (its independent joints): each one's own and
        those of the mimic joints following it (q = m q_k + o within theirs, |m qd_k| and
        |m qdd_k| within theirs), ``margin`` of the range kept free at both ends."""
        n = model.n
        lower, upper = np.full(n, -np.inf), np.full(n, np.inf)
        speed, acceleration = np.full(n, np.inf), np.full(n, np.inf)
        for joint, (k, m, o), mimic in zip(model.joints, model.coordinates, model.mimics or (None,) * n):
            if m == 0.0:  # held at its offset: no limit on q_k
                continue
            ends = sorted((np.array(joint.position_limits) - o) / m)
            lower[k], upper[k] = max(lower[k], ends[0]), min(upper[k], ends[1])
            own = mimic is None  # a coordinate's own joint: the defaults where it gives none
            if joint.velocity_limit or own:
                speed[k] = min(speed[k], (joint.velocity_limit or DEFAULT_SPEED) / abs(m))
            if joint.acceleration_limit or own:
                acceleration[k] = min(acceleration[k], (joint.acceleration_limit or DEFAULT_ACCELERATION) / abs(m))
        room = margin * np.maximum(upper - lower, 0.0)
        return cls(lower + room, upper - room, speed, acceleration)


def shaped(free: np.ndarray, n: int, harmonics: int, period: float, limits: Limits) -> FourierTrajectory:
    """The trajectory of free coefficients (harmonics 2..K), at rest at t = 0, scaled to
    the limits and centred in the position ranges."""
    free = free.reshape(2, n, harmonics - 1)
    l = np.arange(2, harmonics + 1)
    a = np.hstack([-free[0].sum(axis=1, keepdims=True), free[0]])
    b = np.hstack([-(free[1] * l).sum(axis=1, keepdims=True), free[1]])
    unit = FourierTrajectory(period, np.zeros(n), a, b)
    Q, QD, QDD = unit.evaluate(np.linspace(0.0, period, CHECK_POINTS_PER_HARMONIC * harmonics, endpoint=False))
    span = Q.max(axis=0) - Q.min(axis=0)
    with np.errstate(divide="ignore"):
        scale = np.min(
            [
                (limits.upper - limits.lower) / span,
                HEADROOM * limits.speed / np.abs(QD).max(axis=0),
                HEADROOM * limits.acceleration / np.abs(QDD).max(axis=0),
            ],
            axis=0,
        )
    scale = np.where(np.isfinite(scale), scale, 0.0)
    q0 = (limits.upper + limits.lower) / 2.0 - scale * (Q.max(axis=0) + Q.min(axis=0)) / 2.0
    return FourierTrajectory(period, q0, a * scale[:, None], b * scale[:, None])


def condition_number(model: RobotModel, base: BaseParameters, trajectory: FourierTrajectory, samples: int) -> float:
    """cond(Y_b) over ``samples`` states of one period."""
    states = trajectory.evaluate(np.linspace(0.0, trajectory.period, samples, endpoint=False))
    Y = base.columns(regressor_batch(model, *states)).reshape(-1, base.count)
    singular = np.linalg.svd(Y, compute_uv=False)
    return float(singular[0] / singular[-1]) if singular[-1] > 0 else math.inf


@dataclass(frozen=True)
class Excitation:
    trajectory: FourierTrajectory
    condition_number: float
    start_condition_number: float  # of the random start, before optimisation
    evaluations: int
    torque: TorqueScaling | None = None  # how the torque limits scaled it down (None: not at all)


def optimise_excitation(
    model: RobotModel,
    period: float = DEFAULT_PERIOD,
    harmonics: int = DEFAULT_HARMONICS,
    seed: int = 0,
    iterations: int = 60,
    samples: int | None = None,
    margin: float = DEFAULT_MARGIN,
    base: BaseParameters | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Excitation:
    """A trajectory within the model's limits minimising the base regressor's condition number;
    ValueError naming the joints whose position range (less ``margin``) is empty.
    ``progress(done, iterations)`` after each of the optimiser's iterations."""
    if not period > 0.0:
        raise ValueError(f"period: must be > 0 s, got {period}")
    if harmonics < 2:
        raise ValueError(f"harmonics: at least 2 are needed to start at rest, got {harmonics}")
    base = base or find_base_parameters(model)
    limits = Limits.of(model, margin)
    locked = [name for name, low, high in zip(model.joint_names, limits.lower, limits.upper) if not high > low]
    if locked:  # its friction (and what only it moves) would not be excited: condition number inf
        within = " and those of the mimic joints following it" if model.mimics else ""
        raise ValueError(f"{', '.join(locked)}: no position range to move in (position_limits{within} less --margin)")
    pose = holding_pose(model, limits.lower, limits.upper, HEADROOM)  # refused at once if not held
    samples = samples or max(4 * harmonics * 2 + 1, 2 * base.count // model.n + 20, 100)
    n = model.n
    evaluations = 0

    def cost(free):
        nonlocal evaluations
        evaluations += 1
        value = condition_number(model, base, shaped(free, n, harmonics, period, limits), samples)
        return math.log(min(value, 1e300))

    start = np.random.default_rng(seed).normal(size=2 * n * (harmonics - 1))
    start_cost = cost(start)
    best = start
    if iterations > 0:  # (minimize spends a gradient, 2 n (harmonics - 1) evaluations, even on none)
        result = minimize(
            cost,
            start,
            method="L-BFGS-B",
            options={"maxiter": iterations, "eps": 1e-6},
            callback=iterations_to(progress, iterations),
        )
        if progress is not None:
            progress(iterations, iterations)  # (the optimiser may stop before its last iteration)
        best = result.x if result.fun < start_cost else start
    checked = np.linspace(0.0, period, CHECK_POINTS_PER_HARMONIC * harmonics, endpoint=False)
    trajectory, torque = within_torque_limits(
        model,
        lambda within: shaped(best, n, harmonics, period, within),
        limits,
        pose,
        lambda trajectory: trajectory.evaluate(checked),
        HEADROOM,
    )
    return Excitation(
        trajectory, condition_number(model, base, trajectory, samples), math.exp(start_cost), evaluations, torque
    )


def iterations_to(progress: Callable[[int, int], None] | None, iterations: int):
    """The optimiser's callback: ``progress(iterations done, iterations)`` after each one
    (None without ``progress``); the first call, (0, iterations), at once."""
    if progress is None:
        return None
    progress(0, iterations)
    done = 0

    def iterated(*_):
        nonlocal done
        done += 1
        progress(min(done, iterations), iterations)

    return iterated


def check_limits(model: RobotModel, trajectory: FourierTrajectory, rate: float, tolerance: float = 1e-9) -> list[str]:
    """Where the trajectory sampled at ``rate`` leaves the model's limits (of its
    coordinates, see ``Limits.of``; torques by rnea, the payload included): empty, nowhere."""
    Q, QD, QDD = trajectory.evaluate(trajectory.times(rate))
    limits = Limits.of(model, 0.0)
    peaks = np.abs(rnea_batch(model, Q, QD, QDD)).max(axis=0)
    problems = []
    for j, (name, torque_limit) in enumerate(zip(model.joint_names, model.torque_limits)):
        if Q[:, j].min() < limits.lower[j] - tolerance or Q[:, j].max() > limits.upper[j] + tolerance:
            problems.append(f"{name}: position outside [{limits.lower[j]:.4f}, {limits.upper[j]:.4f}] rad")
        if np.abs(QD[:, j]).max() > limits.speed[j] * (1 + tolerance):
            problems.append(f"{name}: speed above {limits.speed[j]:.4f} rad/s")
        if np.abs(QDD[:, j]).max() > limits.acceleration[j] * (1 + tolerance):
            problems.append(f"{name}: acceleration above {limits.acceleration[j]:.4f} rad/s^2")
        if torque_limit and peaks[j] > torque_limit * (1 + tolerance):
            problems.append(f"{name}: torque {peaks[j]:.4g} N m, above its limit {torque_limit:g} N m")
    return problems
