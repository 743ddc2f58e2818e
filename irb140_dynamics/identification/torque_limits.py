"""An excitation within the joints' torque limits.

The excitation (``excitation``) is shaped within the position, velocity and acceleration
limits; its torques (the core's ``rnea``: the model's payload, friction and armature
included) may still exceed a joint's ``torque_limit`` (0: none). Then its motion is scaled
down, the joints whose motion enters that joint's torque alike (``torque_sharers``: those
above and below it, not another branch of a tree), by bisection, until the torque is
within ``headroom`` of the limit. A joint's motion is scaled toward the holding pose
(``holding_pose``: within the ranges, the one whose gravity torques are smallest against
the limits), not the middle of its range: at a zero amplitude the arm rests there, so what
can be held there bounds what any motion can do. Where even that pose needs more than
``headroom`` of a limit, no excitation is within it: ValueError naming the joint.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize

from irb140_dynamics.core.dynamics import rnea_batch
from irb140_dynamics.core.model.robot_model import RobotModel

BISECTIONS = 20  # of each amplitude: to 1e-6
HOLDING_ITERATIONS = 50  # of the search for the holding pose (a smooth, small problem)


@dataclass(frozen=True)
class TorqueScaling:
    """How the torque limits scaled a motion down: ``amplitudes`` (n,) of what the other
    limits allow, per joint, toward ``pose`` (the holding pose, rad); the joints that needed
    it, with their peak torque at the full motion and their limit, N m."""

    amplitudes: np.ndarray
    pose: np.ndarray
    needed: tuple[tuple[str, float, float], ...]  # (joint, peak, limit)


def torque_ratios(model: RobotModel, Q, QD, QDD) -> tuple[np.ndarray, np.ndarray]:
    """(max |tau_j| / limit_j (0 where no limit), max |tau_j| [N m]) over the states given."""
    peaks = np.abs(rnea_batch(model, Q, QD, QDD)).max(axis=0)
    limit = np.array(model.torque_limits)
    return np.where(limit > 0.0, peaks / np.where(limit > 0.0, limit, 1.0), 0.0), peaks


def holding_pose(model: RobotModel, lower: np.ndarray, upper: np.ndarray, headroom: float) -> np.ndarray:
    """The pose within [lower, upper] whose torques at rest are smallest against the torque
    limits (least squares of the ratios, searched from the middle of the ranges; the middle
    itself when the search finds none better in the largest ratio). ValueError naming the
    joint whose ratio there is beyond ``headroom``."""
    middle = (lower + upper) / 2.0
    limit = np.array(model.torque_limits)
    weight = np.where(limit > 0.0, 1.0 / np.where(limit > 0.0, limit, 1.0), 0.0)
    n, step = model.n, 1e-6

    def at_rest(Q):
        zeros = np.zeros_like(Q)
        return rnea_batch(model, Q, zeros, zeros) * weight

    def cost(q):
        probes = np.vstack([q, q + step * np.eye(n)])  # the pose and a step in each joint
        r = at_rest(probes)
        return float(r[0] @ r[0]), 2.0 * ((r[1:] - r[0]) / step) @ r[0]

    pose = middle
    if weight.any():
        found = minimize(
            cost,
            middle,
            jac=True,
            method="L-BFGS-B",
            bounds=list(zip(lower, upper)),
            options={"maxiter": HOLDING_ITERATIONS},
        ).x
        found = np.clip(found, lower, upper)
        if np.abs(at_rest(found[None])).max() < np.abs(at_rest(middle[None])).max():
            pose = found
    ratios = np.abs(at_rest(pose[None])[0])
    j = int(np.argmax(ratios))
    if ratios[j] > headroom:
        raise ValueError(
            f"{model.joint_names[j]}: at rest within the position ranges it needs {ratios[j] * limit[j]:.4g} N m "
            f"in the pose found to need least, beyond {100 * headroom:g} % of its torque limit {limit[j]:g} N m: "
            "no excitation is within it"
        )
    return pose


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


def toward(limits, pose: np.ndarray, amplitudes: np.ndarray):
    """``limits`` (an ``excitation.Limits``) shrunk by ``amplitudes`` toward ``pose``: the
    position ranges about it, the velocity and acceleration limits alike."""
    return replace(
        limits,
        lower=pose + amplitudes * (limits.lower - pose),
        upper=pose + amplitudes * (limits.upper - pose),
        speed=amplitudes * limits.speed,
        acceleration=amplitudes * limits.acceleration,
    )


def within_torque_limits(model: RobotModel, shape: Callable, limits, pose, states: Callable, headroom: float):
    """(the trajectory ``shape(limits)`` scaled toward ``pose`` until its torques at
    ``states(trajectory)`` are within ``headroom`` of every limit, the TorqueScaling or None
    when the full motion is within): while a joint is beyond, its ``torque_sharers`` are
    scaled alike, by bisection; if that does not settle, every joint alike."""
    n = model.n

    def ratios(amplitudes):
        return torque_ratios(model, *states(shape(toward(limits, pose, amplitudes))))

    amplitudes = np.ones(n)
    over, peaks = ratios(amplitudes)
    if over.max() <= headroom:
        return shape(limits), None
    limit = model.torque_limits
    needed = {}
    for _ in range(2 * n):
        over, _ = ratios(amplitudes)
        j = int(np.argmax(over))
        if over[j] <= headroom:
            break
        needed.setdefault(j, (model.joint_names[j], float(peaks[j]), float(limit[j])))
        amplitudes = _bisected(amplitudes, torque_sharers(model, j), lambda a, j=j: ratios(a)[0][j] <= headroom)
    else:  # not settled: every joint alike (zero is within: the holding pose)
        amplitudes = _bisected(amplitudes, np.arange(n), lambda a: ratios(a)[0].max() <= headroom)
    scaling = TorqueScaling(amplitudes, pose, tuple(needed[j] for j in sorted(needed)))
    return shape(toward(limits, pose, amplitudes)), scaling


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
