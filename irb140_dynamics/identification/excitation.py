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
is then scaled down, every joint alike, until its torques (rnea, the payload included) are
within 98 % of the torque limits.

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

DEFAULT_PERIOD = 10.0  # s
DEFAULT_HARMONICS = 5
DEFAULT_MARGIN = 0.05  # of each joint's position range, kept free at both ends
DEFAULT_SPEED = 1.0  # rad/s where a joint gives no velocity limit
DEFAULT_ACCELERATION = 5.0  # rad/s^2 where a joint gives no acceleration limit
CHECK_POINTS_PER_HARMONIC = 100  # limit checks: points per period of the highest harmonic
HEADROOM = 0.98  # of the velocity, acceleration and torque limits: peaks between check points stay within
BISECTIONS = 20  # of the amplitude that keeps the torques within their limits: to 1e-6


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


def shaped(
    free: np.ndarray, n: int, harmonics: int, period: float, limits: Limits, amplitude: float = 1.0
) -> FourierTrajectory:
    """The trajectory of free coefficients (harmonics 2..K), at rest at t = 0, scaled to
    the limits (times ``amplitude``, at most 1) and centred in the position ranges."""
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
    scale = amplitude * np.where(np.isfinite(scale), scale, 0.0)
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


@dataclass(frozen=True)
class TorqueScaling:
    """The motion scaled down so that every joint's torque stays within HEADROOM of its
    torque limit: ``amplitudes`` (n,) of what the other limits allow, per joint; the joints
    that needed it, with their peak torque at the full motion and their limit, N m."""

    amplitudes: np.ndarray
    needed: tuple[tuple[str, float, float], ...]  # (joint, peak, limit)


def peak_torques(model: RobotModel, trajectory: FourierTrajectory, samples: int) -> np.ndarray:
    """max |tau| per joint [N m] over ``samples`` states of one period (rnea: the model's
    payload, friction and armature included)."""
    t = np.linspace(0.0, trajectory.period, samples, endpoint=False)
    return np.abs(rnea_batch(model, *trajectory.evaluate(t))).max(axis=0)


def torque_sharers(model: RobotModel, j: int) -> np.ndarray:
    """The coordinates whose motion enters coordinate j's torque: those of every joint at,
    above or below joint j or a mimic joint following it (a branch beside them adds nothing)."""
    parent = model.parent
    count = len(parent)
    chain = []  # per joint, itself and its ancestors
    for i in range(count):
        chain.append({i} | (chain[parent[i]] if parent[i] >= 0 else set()))
    carriers = [i for i, (k, _, _) in enumerate(model.coordinates) if k == j]
    related = {d for d in range(count) for i in carriers if i in chain[d] or d in chain[i]}
    return np.array(sorted({model.coordinates[d][0] for d in related}))


def within_torque_limits(
    model: RobotModel, free: np.ndarray, harmonics: int, period: float, limits: Limits
) -> tuple[FourierTrajectory, TorqueScaling | None]:
    """``shaped(free, ...)`` scaled down until every joint's torque is within HEADROOM of its
    limit (0: none): while a joint is beyond, the joints sharing its torque (see
    ``torque_sharers``) are scaled alike, by bisection, until it is within; if that does not
    settle, every joint alike. ValueError naming a joint whose torque holding the middle of
    the ranges (where a zero amplitude rests) is already beyond."""
    n = model.n
    limit = np.array(model.torque_limits)
    limited = limit > 0.0
    samples = CHECK_POINTS_PER_HARMONIC * harmonics

    def ratios(amplitudes):
        peaks = peak_torques(model, shaped(free, n, harmonics, period, limits, amplitudes), samples)
        return np.where(limited, peaks / np.where(limited, limit, 1.0), 0.0), peaks

    amplitudes = np.ones(n)
    over, peaks = ratios(amplitudes)
    if over.max() <= HEADROOM:
        return shaped(free, n, harmonics, period, limits), None
    held, torques = ratios(np.zeros(n))
    if held.max() > HEADROOM:
        raise ValueError(_unholdable(model, int(np.argmax(held)), torques[int(np.argmax(held))]))
    needed = {}
    for _ in range(2 * n):
        over, _ = ratios(amplitudes)
        j = int(np.argmax(over))
        if over[j] <= HEADROOM:
            break
        needed.setdefault(j, (model.joint_names[j], float(peaks[j]), float(limit[j])))
        amplitudes = _bisected(amplitudes, torque_sharers(model, j), lambda a, j=j: ratios(a)[0][j] <= HEADROOM)
    else:  # not settled: every joint alike (zero is within: the holding pose)
        amplitudes = _bisected(amplitudes, np.arange(n), lambda a: ratios(a)[0].max() <= HEADROOM)
    scaling = TorqueScaling(amplitudes, tuple(needed[j] for j in sorted(needed)))
    return shaped(free, n, harmonics, period, limits, amplitudes), scaling


def _bisected(amplitudes: np.ndarray, which: np.ndarray, within) -> np.ndarray:
    """``amplitudes`` with those of ``which`` times the largest factor in [0, 1] found by
    bisection for which ``within(amplitudes)`` holds (it holds at 0)."""
    low, high = 0.0, 1.0

    def scaled(factor):
        out = amplitudes.copy()
        out[which] *= factor
        return out

    for _ in range(BISECTIONS):
        middle = (low + high) / 2.0
        low, high = (middle, high) if within(scaled(middle)) else (low, middle)
    return scaled(low)


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
        raise ValueError(f"{', '.join(locked)}: no position range to move in (position_limits less --margin)")
    check_holding_torques(model, limits)
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
    trajectory, torque = within_torque_limits(model, best, harmonics, period, limits)
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


def check_holding_torques(model: RobotModel, limits: Limits) -> None:
    """ValueError naming the first joint whose torque holding the middle of the position
    ranges is beyond HEADROOM of its torque limit: no excitation is within the limits."""
    middle = (limits.lower + limits.upper) / 2.0
    zeros = np.zeros(model.n)
    held = np.abs(rnea_batch(model, [middle], [zeros], [zeros])[0])
    for j, limit in enumerate(model.torque_limits):
        if limit and held[j] > HEADROOM * limit:
            raise ValueError(_unholdable(model, j, held[j]))


def _unholdable(model: RobotModel, j: int, torque: float) -> str:
    limit = model.torque_limits[j]
    return (
        f"{model.joint_names[j]}: holding the middle of the position ranges needs {torque:.4g} N m, beyond "
        f"{100 * HEADROOM:g} % of its torque limit {limit:g} N m: no excitation is within it"
    )


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
