"""Collision sensitivity from data: thresholds that a recording of the arm's normal work never
crosses, and the force at the flange they detect.

``ResidualPeaks`` runs the momentum observer (``observer.MomentumObserver``, as id_node runs
it on every joint state with efforts) over recorded samples and keeps each joint's largest
|r_j| [N m; N for a sliding joint]. ``collision_thresholds`` sets each joint's threshold to
``margin`` times that peak: the recording, played to id_node with those thresholds, raises
no alarm, with that margin.

``DetectableForces`` then says what the thresholds catch: a force F = f d [N] on the flange
origin, d a unit direction in the base frame's axes, loads the joints with
tau = J_v(q)^T d f (J_v the flange's 3 x n linear-velocity Jacobian), and id_node flags it
once the residual has followed it (a first-order lag of time constant 1/K) and some
|tau_j| exceeds threshold_j: from

    f(q, d) = min over j of threshold_j / |J_v(q)^T d|_j.

The figure of a direction is the largest f(q, d) over the recorded poses: a force that large
along d is detected in every one of them. The thresholds are on |r_j|, so d and -d have the
same figure. A pose where no joint feels d (J_v^T d = 0: a force through every joint's
axis) has no finite figure: it is counted in ``undetected`` and the figure is then None.

Units: N, N m, s. No ROS, no files: the tool ``calibrate_collision`` reads and writes.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.kinematics import flange_jacobian, flange_jacobians
from irb140_dynamics.core.model.joints import MAX_TORQUE_LIMIT
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.monitoring.collision import DEFAULT_GAIN, MAX_GAIN, MIN_GAIN, OBSERVER_GAP
from irb140_dynamics.core.monitoring.observer import MomentumObserver

DEFAULT_MARGIN = 1.5  # threshold = margin x the largest |r_j| recorded
AXES = ("+x", "-x", "+y", "-y", "+z", "-z")  # the base frame's directions, in print order
_POSES = 4096  # poses' Jacobians made at once
UNFELT = 1e-12  # a joint loaded by less than this per N (m) does not feel the force


class CalibrationError(ValueError):
    """A recording or a setting the thresholds cannot be set from: one line."""


def usable(q: np.ndarray, qd: np.ndarray, effort: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Masks over samples (rows): (observed: finite q, qd and efforts, what the observer
    takes; no_velocity: a sample without finite velocities, which id_node would read as
    zero; bad_effort: some efforts, not all, non-finite: id_node restarts its observer)."""
    finite_state = np.isfinite(q).all(axis=1)
    has_velocity = np.isfinite(qd).all(axis=1)
    finite_effort = np.isfinite(effort).all(axis=1)
    no_effort = np.isnan(effort).all(axis=1)
    return (
        finite_state & has_velocity & finite_effort,
        finite_state & ~has_velocity,
        finite_state & ~finite_effort & ~no_effort,
    )


class ResidualPeaks:
    """The observer's residual over a recording, sample after sample (``add`` chunk after
    chunk, in the recording's order): each joint's largest |r_j| and when it came."""

    def __init__(self, model: RobotModel, gain: float = DEFAULT_GAIN):
        if not (math.isfinite(gain) and MIN_GAIN <= gain <= MAX_GAIN):
            raise CalibrationError(f"observer gain: must be within {MIN_GAIN:g} to {MAX_GAIN:g} 1/s, got {gain}")
        self.model, self.gain = model, float(gain)
        self.observer = MomentumObserver(model, gain, OBSERVER_GAP)
        self.peak = np.zeros(model.n)  # N m
        self.peak_time = np.full(model.n, np.nan)  # s
        self.observed = 0  # samples the observer took
        self.no_velocity = 0  # samples left out: no velocities
        self.restarts: Counter = Counter()  # MomentumObserver.restarted kinds, and "effort_not_finite"
        self.start = self.end = None  # s: the first and last observed sample's time

    def add(self, time, q, qd, effort) -> None:
        """Samples (time (N,) [s], q, qd, effort (N, n)) in order; those ``usable`` does not
        keep leave the observer as id_node leaves it (a partly non-finite effort restarts it)."""
        observed, no_velocity, bad_effort = usable(q, qd, effort)
        self.no_velocity += int(no_velocity.sum())
        observer, peak, peak_time = self.observer, self.peak, self.peak_time
        time = np.asarray(time, dtype=float)
        for k in range(len(time)):
            if bad_effort[k]:
                observer.reset()
                self.restarts["effort_not_finite"] += 1
                continue
            if not observed[k] or not math.isfinite(time[k]):
                continue
            t = float(time[k])
            try:
                r = np.abs(observer.advance(t, q[k], qd[k], effort[k]))
            except ValueError as error:  # a model the recorded state drives to non-finite torques
                raise CalibrationError(f"at {t:.3f} s: {error}") from None
            if observer.restarted is not None:
                self.restarts[observer.restarted] += 1
            higher = r > peak
            peak[higher], peak_time[higher] = r[higher], t
            self.observed += 1
            self.start = t if self.start is None else self.start
            self.end = t

    @property
    def restarted(self) -> int:
        return sum(self.restarts.values())


def collision_thresholds(peaks: ResidualPeaks, margin: float = DEFAULT_MARGIN) -> np.ndarray:
    """Each joint's threshold: ``margin`` (> 1) times its largest recorded |r_j|.
    CalibrationError when the recording gave the observer nothing to go on, or a
    threshold would be 0 (off in id_node) or beyond what id_node takes."""
    if not (math.isfinite(margin) and margin > 1.0):
        raise CalibrationError(f"margin: must be a finite number > 1, got {margin}")
    names = peaks.model.joint_names
    if peaks.observed < 2 or peaks.observed <= peaks.restarted:
        raise CalibrationError(
            f"the observer ran on {peaks.observed} samples with {peaks.restarted} restarts: "
            "nothing to set thresholds from (the recording needs joint states with positions, "
            "velocities and efforts, at least 10 a second)"
        )
    flat = [name for name, p in zip(names, peaks.peak) if not p > 0.0]
    if flat:
        raise CalibrationError(f"the residual of {', '.join(flat)} never left 0: no threshold can be set from it")
    thresholds = margin * peaks.peak
    over = [f"{name} {x:.3g}" for name, x in zip(names, thresholds) if not x <= MAX_TORQUE_LIMIT]
    if over:
        raise CalibrationError(f"thresholds beyond {MAX_TORQUE_LIMIT:g}: {', '.join(over)}; is it the arm's model?")
    return thresholds


@dataclass(frozen=True)
class DetectableForce:
    """The force along one direction of the base frame that every recorded pose detects."""

    direction: str  # "+x", ..., "-z"
    force: float | None  # N: the worst pose's figure; None when some pose feels none
    time: float | None  # s: the worst pose's (the first pose that feels none, if any)
    joint: int | None  # the joint whose threshold the force crosses first at the worst pose
    undetected: int  # poses where no joint feels a force along the direction


class DetectableForces:
    """The worst pose's detectable force along each of ``AXES`` over the poses ``add``ed."""

    def __init__(self, model: RobotModel, thresholds):
        thresholds = np.asarray(thresholds, dtype=float)
        if thresholds.shape != (model.n,) or not (np.isfinite(thresholds).all() and (thresholds > 0.0).all()):
            raise CalibrationError(f"thresholds: expected {model.n} finite numbers > 0, got {thresholds.tolist()}")
        self.model, self.thresholds = model, thresholds
        self.worst = np.zeros(3)  # N, per axis x, y, z (a direction and its opposite alike)
        self.worst_time = np.full(3, np.nan)
        self.worst_joint = np.zeros(3, dtype=int)
        self.undetected = np.zeros(3, dtype=int)
        self.first_undetected = np.full(3, np.nan)
        self.poses = 0

    def add(self, time, q) -> None:
        """Poses (time (N,) [s], q (N, n)), each with finite values."""
        time, q = np.asarray(time, dtype=float), np.asarray(q, dtype=float)
        for first in range(0, len(time), _POSES):
            self._add(time[first : first + _POSES], flange_jacobians(self.model, q[first : first + _POSES]))

    def _add(self, time, jacobians) -> None:
        for t, jacobian in zip(time, jacobians):
            load = np.abs(jacobian[:3])  # (3, n): N m (N) per N along x, y, z
            felt = np.where(load > UNFELT, load, 0.0) / self.thresholds  # 1/N
            joint = felt.argmax(axis=1)
            sensitivity = felt[np.arange(3), joint]
            for axis in range(3):
                if not sensitivity[axis] > 0.0:
                    if self.undetected[axis] == 0:
                        self.first_undetected[axis] = t
                    self.undetected[axis] += 1
                    continue
                force = 1.0 / sensitivity[axis]
                if force > self.worst[axis]:
                    self.worst[axis], self.worst_time[axis], self.worst_joint[axis] = force, t, joint[axis]
            self.poses += 1

    def result(self) -> list[DetectableForce]:
        """One per direction of ``AXES``, in that order."""
        found = []
        for name in AXES:
            axis = "xyz".index(name[1])
            if self.undetected[axis]:
                found.append(
                    DetectableForce(name, None, float(self.first_undetected[axis]), None, int(self.undetected[axis]))
                )
            elif self.poses:
                worst = float(self.worst[axis])
                found.append(DetectableForce(name, worst, float(self.worst_time[axis]), int(self.worst_joint[axis]), 0))
            else:
                found.append(DetectableForce(name, None, None, None, 0))
        return found


def detectable_force_at(model: RobotModel, q, thresholds, direction) -> float:
    """f(q, d) of the module: the smallest force [N] along the unit ``direction`` (3, base
    axes) at the flange origin that loads some joint beyond its threshold at pose q; inf
    when no joint feels it."""
    d = np.asarray(direction, dtype=float)
    load = np.abs(flange_jacobian(model, q)[:3].T @ (d / np.linalg.norm(d)))
    felt = np.where(load > UNFELT, load, 0.0) / np.asarray(thresholds, dtype=float)
    return math.inf if not felt.max() > 0.0 else float(1.0 / felt.max())
