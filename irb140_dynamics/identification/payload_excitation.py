"""Payload excitation: a wrist motion that makes a payload's ten inertial parameters observable.

The last three joints (the wrist; every joint of a shorter arm) follow the finite Fourier
series of ``excitation``, the others hold a pose (by default the middle of their ranges):
the held joints carry the payload's static load, which tells its mass from its first
moments, and the wrist's turns and accelerations show its inertia. The wrist's motion is
scaled to its limits like ``excitation``'s (position range less ``margin``, 98 % of the
velocity and acceleration limits). The cost is log cond of the payload's regressor
(``payload.payload_regressor``, ten columns) stacked over ``samples`` states of one
period, each joint's rows divided by the arm's peak torque at that joint along the
motion (torque sensors' noise grows with their range) and each column scaled to unit
norm (so that kilograms and kg m^2 weigh alike), minimised by SciPy's L-BFGS-B from a
seeded random start.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.optimize import minimize

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.identification.excitation import (
    DEFAULT_MARGIN,
    Excitation,
    FourierTrajectory,
    Limits,
    iterations_to,
    shaped,
)
from irb140_dynamics.identification.payload import PARAMETER_LABELS, excitation, payload_regressor

WRIST_JOINTS = 3
DEFAULT_PAYLOAD_PERIOD = 10.0  # s
MAX_PAYLOAD_DURATION = 30.0  # s: a load identification is a short routine
MIN_WRIST_TRAVEL = 0.1  # rad: each wrist joint's motion at least this wide
SAMPLES = 120
MAX_CONDITION = 1e3  # above: a parameter (nearly) in the others' span; a good pose gives 4 to 15
WEAKLY_SEEN = 0.01  # sine of the angle between a parameter's column and the others': named when refused


def wrist(model: RobotModel) -> np.ndarray:
    """Indices of the joints that move: the last three (all of them on a shorter arm)."""
    return np.arange(max(model.n - WRIST_JOINTS, 0), model.n)


def payload_limits(model: RobotModel, margin: float = DEFAULT_MARGIN, pose=None) -> Limits:
    """The model's limits with the joints before the wrist pinned at ``pose`` (default: the
    middle of their ranges; the wrist's own values are not used, it moves over its range);
    ValueError naming a pose outside its joint's range, the wrist's included."""
    limits = Limits.of(model, margin)
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


def _trajectory(free, model: RobotModel, harmonics: int, period: float, limits: Limits) -> FourierTrajectory:
    moving = wrist(model)
    full = np.zeros((2, model.n, harmonics - 1))
    full[:, moving, :] = free.reshape(2, len(moving), harmonics - 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return shaped(full.ravel(), model.n, harmonics, period, limits)


def _weighted_regressor(model: RobotModel, trajectory: FourierTrajectory, samples: int = SAMPLES) -> np.ndarray:
    """The payload's regressor over one period, each joint's rows divided by its peak torque."""
    states = trajectory.evaluate(np.linspace(0.0, trajectory.period, samples, endpoint=False))
    Y, tau_arm = payload_regressor(model, *states)
    peak = np.abs(tau_arm).max(axis=0)
    weights = 1.0 / np.maximum(peak, 1e-6 * max(float(peak.max()), 1e-300))
    return (Y * weights[None, :, None]).reshape(-1, Y.shape[-1])


def payload_condition_number(model: RobotModel, trajectory: FourierTrajectory, samples: int = SAMPLES) -> float:
    """cond of the payload's weighted, column-scaled regressor over one period (see above)."""
    stacked = _weighted_regressor(model, trajectory, samples)
    norms = np.linalg.norm(stacked, axis=0)
    if not np.all(norms > 0.0):
        return math.inf
    singular = np.linalg.svd(stacked / norms, compute_uv=False)
    return float(singular[0] / singular[-1]) if singular[-1] > 0 else math.inf


def optimise_payload_excitation(
    model: RobotModel,
    period: float = DEFAULT_PAYLOAD_PERIOD,
    harmonics: int = 5,
    seed: int = 0,
    iterations: int = 40,
    margin: float = DEFAULT_MARGIN,
    pose=None,
    progress: Callable[[int, int], None] | None = None,
) -> Excitation:
    """A wrist motion within the model's limits minimising the payload regressor's condition
    number; ValueError when the wrist's limits leave a joint less than MIN_WRIST_TRAVEL, or
    when the pose leaves the condition number above MAX_CONDITION (naming the parameters).
    ``progress(done, iterations)`` after each of the optimiser's iterations."""
    if not 0.0 < period <= MAX_PAYLOAD_DURATION:
        raise ValueError(f"period: must be within (0, {MAX_PAYLOAD_DURATION:g}] s, got {period}")
    if harmonics < 2:
        raise ValueError(f"harmonics: at least 2 are needed to start at rest, got {harmonics}")
    limits = payload_limits(model, margin, pose)
    evaluations = 0

    def cost(free):
        nonlocal evaluations
        evaluations += 1
        value = payload_condition_number(model, _trajectory(free, model, harmonics, period, limits))
        return math.log(min(value, 1e300))

    start = np.random.default_rng(seed).normal(size=2 * len(wrist(model)) * (harmonics - 1))
    start_cost = cost(start)
    best = start
    if iterations > 0:
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
    trajectory = _trajectory(best, model, harmonics, period, limits)
    travel = np.ptp(trajectory.evaluate(np.linspace(0.0, period, 100 * harmonics))[0], axis=0)
    for j in wrist(model):
        if travel[j] <= MIN_WRIST_TRAVEL:
            raise ValueError(
                f"{model.joints[j].name}: its limits allow a motion of only {travel[j]:.3g} rad, "
                f"{MIN_WRIST_TRAVEL:g} rad needed"
            )
    condition = payload_condition_number(model, trajectory)
    if not condition <= MAX_CONDITION:
        stacked = _weighted_regressor(model, trajectory)
        seen = excitation(stacked.T @ stacked)
        names = ", ".join(PARAMETER_LABELS[k] for k in np.flatnonzero(seen <= max(WEAKLY_SEEN, seen.min())))
        raise ValueError(
            f"pose: at this pose the wrist's motion cannot tell the payload's {names} apart from the others "
            f"(condition number {condition:.3g}): hold another --pose"
        )
    return Excitation(trajectory, condition, math.exp(start_cost), evaluations)
