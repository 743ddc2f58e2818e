"""Payload excitation: a wrist motion designed for the ten inertial parameters of a payload
on the arm at hand, with the standard deviations it promises them at a stated effort noise.

The last three joints (the wrist; every joint of a shorter arm) follow the finite Fourier
series of ``excitation``, the others hold a pose: the held joints carry the payload's static
load, which tells its mass from its first moments, and the wrist's turns, speeds and
accelerations show its inertia. The wrist's motion is scaled to its limits like
``excitation``'s (position range less ``margin``, 98 % of the velocity and acceleration
limits); where a joint's speed or acceleration limit, not its range, bounds it, the centre
of its motion (the wrist's pose) is a design variable too. A wrist joint that states no
acceleration limit (a URDF gives none) is given the one that reaches its velocity limit in
RAMP_TIME (``assumed_accelerations``; at least excitation's DEFAULT_ACCELERATION): the
payload's inertia shows in torques proportional to the wrist's accelerations and to
products of its speeds, and a fixed 5 rad/s^2 leaves a fast wrist's inertia torques below
the noise of a strong drive (1 % of the UR5's 28 N m).

What is optimised is what `identify --payload-only` will know. Its weighted least squares
(``payload``) has the information matrix

    F = sum over joints j of  (rate x duration / S) sum_k Y_kj^T Y_kj / sigma_j^2

Y_kj joint j's row of the payload's regressor (``payload.payload_regressor``, flange frame)
at S states of one period (the rows `identify` uses: a moving joint's where it is fast
enough for its Coulomb model, see ``information``), sigma_j joint j's effort noise per recorded sample
(``EffortNoise``, as the user states it), rate the recording's sample rate and duration
what is recorded (the periods that fit in MAX_PAYLOAD_DURATION); F^-1 is the covariance of
the ten parameters, and sqrt(diag F^-1) what the motion promises. The cost is
log trace((D F D)^-1), D = UNIT_SCALE (1 kg, 0.1 m out): the sum of the parameters'
variances in units of a 1 kg body 0.1 m out, so that no parameter is left to the noise
(A-optimal design). Unless given, the held pose (the middle of the ranges or one of POSES
random poses within them, preferring those where the arm's own torques take at most
MAX_TORQUE_USE of any torque limit, leaving the rest to the payload) and the period (one
of PERIODS: which band of frequencies uses the wrist's speed and acceleration limits best
depends on their ratio) are chosen together with the motion: for each period, the pose
where the best of SCOUTS random motions tells the most; at each of these, the best of
STARTS random motions improved by SciPy's L-BFGS-B for 1/SCREEN of the iterations; the
FINALISTS best of them improved for the iterations each, the best result kept. The period
is decided by optimised motions, not random ones: a random motion's score ranks the periods
poorly (the optimum is often at the shortest period, where the wrist's accelerations are
used most), and a design that chose its period from random motions alone gave, over its
own seeds, promises up to 4 times apart on the same arm.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.identification.effort_noise import DEFAULT_EFFORT_NOISE, EffortNoise
from irb140_dynamics.identification.excitation import (
    CHECK_POINTS_PER_HARMONIC,
    DEFAULT_ACCELERATION,
    DEFAULT_MARGIN,
    DEFAULT_SPEED,
    FourierTrajectory,
    Limits,
    iterations_to,
    shaped,
)
from irb140_dynamics.identification.payload import (
    MAX_RELATIVE_STD,
    PARAMETER_LABELS,
    UNIT_SCALE,
    excitation,
    payload_regressor,
)
from irb140_dynamics.identification.pipeline import SLOW_SPEEDS
from irb140_dynamics.identification.selection import rows_used
from irb140_dynamics.identification.signals import FilterDesign

WRIST_JOINTS = 3
PERIODS = (2.0, 3.0, 5.0, 7.5, 10.0, 15.0)  # s the design chooses among (each divides 30 s)
DEFAULT_PAYLOAD_HARMONICS = 3
MAX_PAYLOAD_DURATION = 30.0  # s: a load identification is a short routine
DEFAULT_RECORD_RATE = 500.0  # Hz: joint states as drivers commonly publish them
MIN_WRIST_TRAVEL = 0.1  # rad: each wrist joint's motion at least this wide
POSES = 8  # random held poses tried besides the middle of the ranges (no --pose given)
SCOUTS = 3  # of them scoring each held pose and period
SCREEN = 4  # each period's motion is first optimised for 1/SCREEN of the iterations
FINALISTS = 2  # the best periods after the screen, each optimised on
STARTS = 8  # random motions tried before the optimisation
MAX_TORQUE_USE = 0.3  # of a torque limit the arm's own torques may take at a chosen pose: the rest is the payload's
SAMPLES = 80  # states of one period the design sums over
MAX_CONDITION = 1e3  # above: a parameter (nearly) in the others' span; a good pose gives 4 to 15
WEAKLY_SEEN = 0.01  # sine of the angle between a parameter's column and the others': named when refused
RAMP_TIME = 0.25  # s: a wrist joint without an acceleration limit reaches its velocity limit in this time
# (the IRB-140's stated limits do, to 1 %; Franka's reach theirs in 0.13 to 0.15 s)
UNITS = ("kg", "kg m", "kg m", "kg m", "kg m^2", "kg m^2", "kg m^2", "kg m^2", "kg m^2", "kg m^2")


@dataclass(frozen=True, eq=False)
class PayloadExcitation:
    trajectory: FourierTrajectory
    condition_number: float  # of the noise-weighted, column-scaled regressor (1 is ideal)
    start_condition_number: float  # of the random start, before optimisation
    evaluations: int
    std: np.ndarray  # (10,) expected standard deviations of phi (flange frame, inertia about its origin)
    sigma: np.ndarray  # (n,) N m: the effort noise per joint the design assumed
    noise: EffortNoise
    rate: float  # Hz
    duration: float  # s
    assumed: dict[str, float]  # rad/s^2: the acceleration limits assumed for wrist joints that state none
    unlimited_speed: tuple[str, ...] = ()  # the wrist joints that state no velocity limit (DEFAULT_SPEED used)

    def expectation(self) -> list[str]:
        """What the motion promises, as lines to print (or to write as comments)."""
        values = ", ".join(f"{label} +- {s:.2g} {unit}" for label, s, unit in zip(PARAMETER_LABELS, self.std, UNITS))
        speeds = f"no velocity limit given for {', '.join(self.unlimited_speed)}: assumed {DEFAULT_SPEED:g} rad/s"
        accelerations = (
            f"no acceleration limit given for {', '.join(self.assumed)}: assumed "
            f"{', '.join(f'{a:.3g}' for a in self.assumed.values())} rad/s^2 (the velocity limit reached in "
            f"{RAMP_TIME:g} s, at least {DEFAULT_ACCELERATION:g}"
        )
        return [
            *([f"{speeds} (a params file's <joint>.velocity_limit sets yours)"] if self.unlimited_speed else []),
            *([f"{accelerations}; a params file's <joint>.acceleration_limit sets yours)"] if self.assumed else []),
            f"expected at an effort noise of {self.noise} ({', '.join(f'{s:.3g}' for s in self.sigma)} N m), "
            f"recorded at {self.rate:g} Hz for {self.duration:g} s: one standard deviation of",
            f"  {values}",
            "  (flange frame, inertia about its origin; identify --payload-only refuses a parameter whose deviation "
            f"exceeds {100 * MAX_RELATIVE_STD:g} % of the payload's scale)",
        ]


def wrist(model: RobotModel) -> np.ndarray:
    """Indices of the joints that move: the last three (all of them on a shorter arm)."""
    return np.arange(max(model.n - WRIST_JOINTS, 0), model.n)


def assumed_accelerations(model: RobotModel) -> dict[str, float]:
    """{name: rad/s^2} for each wrist joint that states no acceleration limit: the acceleration
    that reaches its velocity limit in RAMP_TIME, at least DEFAULT_ACCELERATION (and that
    where it states no velocity limit either)."""
    return {
        model.joints[j].name: max(DEFAULT_ACCELERATION, model.joints[j].velocity_limit / RAMP_TIME)
        for j in wrist(model)
        if not model.joints[j].acceleration_limit
    }


def with_assumed_accelerations(model: RobotModel) -> RobotModel:
    """The model with ``assumed_accelerations`` as its wrist joints' acceleration limits: the
    limits the payload motion is designed, and checked, within."""
    assumed = assumed_accelerations(model)
    if not assumed:
        return model
    joints = tuple(replace(j, acceleration_limit=assumed[j.name]) if j.name in assumed else j for j in model.joints)
    return replace(model, joints=joints)


def payload_limits(model: RobotModel, margin: float = DEFAULT_MARGIN, pose=None) -> Limits:
    """The model's limits (its wrist's acceleration limits ``with_assumed_accelerations``) with
    the joints before the wrist pinned at ``pose`` (default: the middle of their ranges; the
    wrist's own values are not used, it moves over its range); ValueError naming a pose
    outside its joint's range, the wrist's included."""
    limits = Limits.of(with_assumed_accelerations(model), margin)
    held = np.setdiff1d(np.arange(model.n), wrist(model))
    centre = (limits.lower + limits.upper) / 2.0
    pose = centre if pose is None else np.asarray(pose, dtype=float)
    if pose.shape != (model.n,) or not np.all(np.isfinite(pose)):
        raise ValueError(f"pose: expected {model.n} finite joint positions, got {np.ravel(pose).tolist()}")
    lower, upper = limits.lower.copy(), limits.upper.copy()
    for j, joint in enumerate(model.joints):
        low, high = joint.position_limits
        if not low <= pose[j] <= high:
            raise ValueError(f"pose: {joint.name} at {pose[j]:g} rad is outside [{low:g}, {high:g}] rad")
    lower[held] = upper[held] = pose[held]
    return Limits(lower, upper, limits.speed, limits.acceleration)


def recorded(period: float, periods: int | None = None) -> float:
    """The seconds recorded: ``periods`` periods, by default as many as MAX_PAYLOAD_DURATION holds."""
    return (max(int(MAX_PAYLOAD_DURATION / period + 1e-9), 1) if periods is None else periods) * period


def period_choices(period: float | None = None, periods: int | None = None) -> list[float]:
    """The periods [s] the design may use: ``period`` or PERIODS, those whose ``periods``
    repetitions (default: as many as fit) last at most MAX_PAYLOAD_DURATION."""
    given = [period] if period is not None else PERIODS
    return [T for T in given if 0.0 < recorded(T, periods) <= MAX_PAYLOAD_DURATION * (1 + 1e-12)]


def held_poses(model: RobotModel, margin: float, rng: np.random.Generator) -> list[np.ndarray]:
    """Poses the design may hold: the middle of the ranges, then POSES drawn uniformly within
    the ranges less ``margin`` (the wrist's values are the middle's: it moves over its range)."""
    limits = Limits.of(model, margin)
    middle = (limits.lower + limits.upper) / 2.0
    held = np.setdiff1d(np.arange(model.n), wrist(model))
    poses = [middle]
    for _ in range(POSES if len(held) else 0):
        pose = middle.copy()
        pose[held] = rng.uniform(limits.lower[held], limits.upper[held])
        poses.append(pose)
    return poses


def _trajectory(free, model: RobotModel, harmonics: int, period: float, limits: Limits) -> FourierTrajectory:
    """The wrist's motion of ``free``: its Fourier coefficients, then one number per wrist
    joint placing the motion's centre within the room its range leaves (tanh: -1 to 1)."""
    moving = wrist(model)
    coefficients, placement = free[: -len(moving)], free[-len(moving) :]
    full = np.zeros((2, model.n, harmonics - 1))
    full[:, moving, :] = coefficients.reshape(2, len(moving), harmonics - 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        trajectory = shaped(full.ravel(), model.n, harmonics, period, limits)
    Q = trajectory.evaluate(np.linspace(0.0, period, CHECK_POINTS_PER_HARMONIC * harmonics, endpoint=False))[0]
    room = np.maximum(np.minimum(Q.min(axis=0) - limits.lower, limits.upper - Q.max(axis=0)), 0.0)
    q0 = trajectory.q0.copy()
    q0[moving] += np.tanh(placement) * room[moving] * (1.0 - 1e-9)
    return FourierTrajectory(period, q0, trajectory.a, trajectory.b)


def information(
    model: RobotModel,
    trajectory: FourierTrajectory,
    noise: EffortNoise = DEFAULT_EFFORT_NOISE,
    rate: float = DEFAULT_RECORD_RATE,
    duration: float | None = None,
    samples: int = SAMPLES,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(F (10, 10), sigma (n,), peak (n,)): the information matrix of the payload's ten
    parameters that a recording of ``duration`` s (default one period) at ``rate`` Hz gives
    at that noise, each joint's noise [N m] and the arm's own peak torque [N m] along the motion.
    Only the rows `identify` uses count: a moving joint's where it is fast enough for the
    Coulomb model throughout its filter's window (``selection.rows_used``, at identify's
    default cut-off for that rate), and every row of a joint held still."""
    duration = trajectory.period if duration is None else duration
    states = trajectory.evaluate(np.linspace(0.0, trajectory.period, samples, endpoint=False))
    Y, tau_arm = payload_regressor(model, *states)
    peak = np.abs(tau_arm).max(axis=0)
    sigma = noise.sigma(model, peak)
    filter_design = FilterDesign.of(rate)
    used = rows_used(states[1], states[2], SLOW_SPEEDS * model.smoothing_velocity, filter_design.half / rate)
    used |= ~used.any(axis=0)  # a joint held still: all its rows
    weighted = (Y * (used / sigma)[:, :, None]).reshape(-1, Y.shape[-1])
    return weighted.T @ weighted * (rate * duration / samples), sigma, peak


def _torque_use(model: RobotModel, peak: np.ndarray) -> float:
    """The largest fraction of a joint's torque limit the arm's own torques take (0: no limits)."""
    limits = np.array(model.torque_limits, dtype=float)
    limited = limits > 0.0
    return float((peak[limited] / limits[limited]).max()) if limited.any() else 0.0


def _a_optimal(F: np.ndarray) -> float:
    """log of the sum of the parameters' variances in UNIT_SCALE units (inf when singular)."""
    eigenvalues = np.linalg.eigvalsh(F * np.outer(UNIT_SCALE, UNIT_SCALE))
    if not eigenvalues[0] > 1e-12 * max(eigenvalues[-1], 1e-300):
        return math.inf
    return math.log(float(np.sum(1.0 / eigenvalues)))


def _condition(F: np.ndarray) -> float:
    """cond of the weighted regressor, its columns scaled to unit norm: sqrt(cond(D F D))."""
    diagonal = np.diag(F)
    if not np.all(diagonal > 0.0):
        return math.inf
    scale = 1.0 / np.sqrt(diagonal)
    eigenvalues = np.linalg.eigvalsh(F * np.outer(scale, scale))
    return float(math.sqrt(eigenvalues[-1] / eigenvalues[0])) if eigenvalues[0] > 0 else math.inf


def optimise_payload_excitation(
    model: RobotModel,
    period: float | None = None,
    harmonics: int = DEFAULT_PAYLOAD_HARMONICS,
    seed: int = 0,
    iterations: int = 40,
    margin: float = DEFAULT_MARGIN,
    pose=None,
    noise: EffortNoise = DEFAULT_EFFORT_NOISE,
    rate: float = DEFAULT_RECORD_RATE,
    periods: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> PayloadExcitation:
    """A wrist motion within the model's limits for the payload's ten parameters (see the
    module's docstring), recorded for ``periods`` periods (default: as many as 30 s hold);
    ValueError when the wrist's limits leave a joint less than MIN_WRIST_TRAVEL, or when
    the pose leaves the condition number above MAX_CONDITION (naming the parameters).
    ``iterations``: the optimiser's for each of the FINALISTS (and 1/SCREEN of them for each
    period); ``progress(done, total)`` after each of the optimiser's iterations."""
    if period is not None and not 0.0 < period <= MAX_PAYLOAD_DURATION:
        raise ValueError(f"period: must be within (0, {MAX_PAYLOAD_DURATION:g}] s, got {period}")
    if harmonics < 2:
        raise ValueError(f"harmonics: at least 2 are needed to start at rest, got {harmonics}")
    choices = period_choices(period, periods)
    if not choices:
        given = f"{period:g} s" if period is not None else f"{min(PERIODS):g} s at least"
        raise ValueError(f"periods: {periods} x {given} is more than {MAX_PAYLOAD_DURATION:g} s")
    assumed = assumed_accelerations(model)
    unlimited_speed = tuple(model.joints[j].name for j in wrist(model) if not model.joints[j].velocity_limit)
    model = with_assumed_accelerations(model)
    moving = wrist(model)
    rng = np.random.default_rng(seed)
    starts = [np.r_[rng.normal(size=2 * len(moving) * (harmonics - 1)), np.zeros(len(moving))] for _ in range(STARTS)]
    evaluations = 0

    def design(free, limits, period) -> tuple[FourierTrajectory, np.ndarray, np.ndarray, np.ndarray]:
        trajectory = _trajectory(free, model, harmonics, period, limits)
        return trajectory, *information(model, trajectory, noise, rate, recorded(period, periods))

    def cost(free, limits, period, with_use=False):
        nonlocal evaluations
        evaluations += 1
        _, F, _, peak = design(free, limits, period)
        value = min(_a_optimal(F), 700.0)
        return (_torque_use(model, peak) > MAX_TORQUE_USE, value) if with_use else value

    # the held pose and the period too, unless given: for each period the pose where random
    # motions tell the most, its best start optimised briefly; the FINALISTS best optimised on
    poses = held_poses(model, margin, rng) if pose is None else [pose]
    screen = iterations // SCREEN
    total, spent = iterations * min(FINALISTS, len(choices)) + len(choices) * screen, 0

    def optimised(found, limits, period, budget):
        nonlocal spent
        if budget <= 0:
            return found
        options = {"maxiter": budget, "maxfun": budget * (len(found[1]) + 1), "eps": 1e-6}
        overall = None if progress is None else lambda done, _, s=spent: progress(s + done, total)
        spent += budget
        callback = iterations_to(overall, budget)
        result = minimize(cost, found[1], args=(limits, period), method="L-BFGS-B", options=options, callback=callback)
        return min(found, (result.fun, result.x), key=lambda c: c[0])

    screened = []
    for period in choices:
        limits = [payload_limits(model, margin, p) for p in poses]
        scores = [min(cost(x, lim, period, True) for x in starts[:SCOUTS]) for lim in limits]
        limits = limits[min(range(len(poses)), key=scores.__getitem__)]
        costs = [cost(x, limits, period) for x in starts]
        found = optimised((min(costs), starts[int(np.argmin(costs))]), limits, period, screen)
        screened.append((found, limits, period))
    screened.sort(key=lambda c: c[0][0])
    results = [
        (optimised(found, limits, period, iterations), limits, period) for found, limits, period in screened[:FINALISTS]
    ]
    (_, best), limits, period = min(results, key=lambda c: c[0][0])
    if progress is not None:
        progress(total, total)  # (an optimiser may stop early)
    start_condition = _condition(design(starts[0], limits, period)[1])
    trajectory, F, sigma, _ = design(best, limits, period)
    travel = np.ptp(trajectory.evaluate(np.linspace(0.0, period, 100 * harmonics))[0], axis=0)
    for j in moving:
        if travel[j] <= MIN_WRIST_TRAVEL:
            raise ValueError(
                f"{model.joints[j].name}: its limits allow a motion of only {travel[j]:.3g} rad, "
                f"{MIN_WRIST_TRAVEL:g} rad needed"
            )
    condition = _condition(F)
    if not condition <= MAX_CONDITION:
        seen = excitation(F)
        names = ", ".join(PARAMETER_LABELS[k] for k in np.flatnonzero(seen <= max(WEAKLY_SEEN, seen.min())))
        raise ValueError(
            f"pose: at this pose the wrist's motion cannot tell the payload's {names} apart from the others "
            f"(condition number {condition:.3g}): hold another --pose"
        )
    std = np.sqrt(np.diag(np.linalg.inv(F)))
    return PayloadExcitation(
        trajectory,
        condition,
        start_condition,
        evaluations,
        std,
        sigma,
        noise,
        rate,
        recorded(period, periods),
        assumed,
        unlimited_speed,
    )
