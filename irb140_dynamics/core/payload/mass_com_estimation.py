"""What is on the flange: the payload's mass and centre of mass from efforts at rest.

At rest the measured efforts hold the arm and the payload against gravity. The payload's
part is linear in phi = [m, m c_x, m c_y, m c_z] (c in the flange frame):

    effort - g_arm(q) = Y(q) phi,   Y = [-J_v^T g,  -J_w^T (R e_k x g) for k = x, y, z]

with J_v, J_w the flange Jacobian's rows, R the flange orientation and g the gravity
vector, all in the base frame (g_arm: the model's own gravity torques, payload removed).
"At rest" is slower than a rest velocity, where the model's tanh-smoothed Coulomb friction
is far from zero: RestDetector takes the model's friction at each joint state's measured
velocity off its efforts (nothing at qd = 0). Weighted least squares over the rest poses
(each torque weighted by the inverse of its average's standard error, when the rest had
several joint states) gives phi, its standard deviations from the residual, and the
condition number of the (column-scaled) weighted Y.

The payload's inertia does not show at rest: it is not estimated.

Refusals (EstimationError, saying what to do): fewer than MIN_POSES poses; poses too
similar to determine phi (condition number above MAX_CONDITION: the message says which
line of the CoM is undetermined and which wrist motion would help); an implausible result
(mass <= 0, or the CoM more than MAX_COM_DISTANCE from the flange). A rest without efforts
is no sample: RestDetector counts its pose in ``without_effort``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.dynamics import gravity
from irb140_dynamics.core.kinematics import flange_jacobian, flange_pose
from irb140_dynamics.core.model.friction import JointFriction
from irb140_dynamics.core.model.rigid_body import RigidBody
from irb140_dynamics.core.model.robot_model import RobotModel

MIN_POSES = 3  # 4 unknowns; each pose sees the payload through 2-3 independent torques
MAX_CONDITION = 1e3  # of Y with columns scaled to unit norm
MAX_COM_DISTANCE = 0.5  # m from the flange origin: beyond it the estimate is refused


class EstimationError(ValueError):
    """The poses cannot determine the payload, or the result is implausible."""


@dataclass(frozen=True)
class RestSample:
    """One pose at rest: joint positions [rad] and the averaged efforts [N m] (the model's
    friction at each joint state's velocity taken off)."""

    q: np.ndarray
    effort: np.ndarray
    count: int  # joint states averaged
    effort_error: np.ndarray | None = None  # standard error of the averaged efforts [N m]


@dataclass(frozen=True)
class PayloadEstimate:
    mass: float  # kg
    com: tuple[float, float, float]  # m, flange frame
    mass_std: float
    com_std: tuple[float, float, float]
    residual_rms: float  # N m
    poses: int
    condition: float

    @property
    def body(self) -> RigidBody:
        return RigidBody(self.mass, self.com)

    def summary(self) -> str:
        c, s = self.com, self.com_std
        return (
            f"payload {self.mass:.3f} +- {self.mass_std:.3f} kg at "
            f"({c[0]:.4f}, {c[1]:.4f}, {c[2]:.4f}) +- ({s[0]:.4f}, {s[1]:.4f}, {s[2]:.4f}) m; "
            f"residual RMS {self.residual_rms:.3f} N m; {self.poses} poses; condition {self.condition:.1f}"
        )


def payload_columns(model: RobotModel, q) -> np.ndarray:
    """Y(q), n x 4: the static torques of a unit [m, m c_x, m c_y, m c_z] on the flange."""
    J = flange_jacobian(model, q)
    R = flange_pose(model, q)[:3, :3]
    g = np.array(model.gravity)
    columns = [-J[:3].T @ g] + [-J[3:].T @ np.cross(R[:, k], g) for k in range(3)]
    return np.column_stack(columns)


def estimate_payload(model: RobotModel, samples: list[RestSample]) -> PayloadEstimate:
    """Least-squares payload from rest samples; EstimationError when it cannot be trusted."""
    if len(samples) < MIN_POSES:
        raise EstimationError(
            f"{len(samples)} rest poses, at least {MIN_POSES} needed: stop the arm in more poses "
            "that differ in the wrist (joints 4, 5, 6)"
        )
    empty = model.with_payload(RigidBody())
    weights = np.concatenate([_weights(s) for s in samples])
    Y = np.vstack([payload_columns(model, s.q) for s in samples]) * weights[:, None]
    b = np.concatenate([np.asarray(s.effort, dtype=float) - gravity(empty, s.q) for s in samples]) * weights
    scale = np.linalg.norm(Y, axis=0)
    if np.any(scale == 0.0):
        raise EstimationError("the payload does not load any joint in these poses (is gravity zero?)")
    U, sigma, Vt = np.linalg.svd(Y / scale, full_matrices=False)
    condition = sigma[0] / sigma[-1] if sigma[-1] > 0 else math.inf
    if condition > MAX_CONDITION:
        advice = _advice(Vt[-1], scale)
        raise EstimationError(f"the poses are too similar (condition number {condition:.3g}): {advice}")
    phi = (Vt.T @ ((U.T @ b) / sigma)) / scale
    residual = b - Y @ phi
    dof = max(len(b) - 4, 1)
    variance = residual @ residual / dof
    covariance = variance * np.linalg.inv(Y.T @ Y)
    mass = float(phi[0])
    if mass <= 0.0:
        raise EstimationError(f"implausible: estimated mass {mass:.3f} kg <= 0 (is a payload mounted?)")
    com = phi[1:] / mass
    if np.linalg.norm(com) > MAX_COM_DISTANCE:
        raise EstimationError(
            f"implausible: CoM {np.round(com, 3).tolist()} m is more than {MAX_COM_DISTANCE} m from the "
            "flange (the plausibility limit, docs/payload_check_node.md): check that the samples are of the "
            "payload at rest (not held or pushed), that the model's own link inertials and friction are right "
            "(identify them), and that the payload really reaches that far out"
        )
    # first-order propagation to c = (m c) / m
    gradient = np.hstack([-com[:, None] / mass, np.eye(3) / mass])
    com_std = np.sqrt(np.maximum(np.diag(gradient @ covariance @ gradient.T), 0.0))
    return PayloadEstimate(
        mass,
        tuple(com.tolist()),
        float(math.sqrt(max(covariance[0, 0], 0.0))),
        tuple(com_std.tolist()),
        float(math.sqrt(np.mean((residual / weights) ** 2))),
        len(samples),
        float(condition),
    )


def _weights(sample: RestSample) -> np.ndarray:
    """1 / the standard error of each averaged effort (floored at 1e-4 N m); ones if unknown."""
    if sample.effort_error is None:
        return np.ones(len(sample.effort))
    return 1.0 / np.maximum(sample.effort_error, 1e-4)


def _advice(weak: np.ndarray, scale: np.ndarray) -> str:
    """What the weakest direction of the column-scaled [m, m c] says to do."""
    if np.argmax(np.abs(weak)) == 0:
        return "the mass is not determined: stop the arm in poses with the flange at different reaches"
    line = weak[1:] / scale[1:]  # in m c, the flange frame: where gravity pointed in every pose
    line = np.round(line / np.linalg.norm(line) * np.sign(line[np.argmax(np.abs(line))]), 2) + 0.0  # no -0.00
    what = (
        f"the CoM along ({line[0]:.2f}, {line[1]:.2f}, {line[2]:.2f}) in the flange frame is not "
        "determined (gravity pulled the same way in the flange frame in every pose: poses that differ "
        "only in joint 1 do): "
    )
    if abs(line[2]) > 0.9:
        return what + "tilt the wrist (joint 5) so that the flange z axis points in different directions"
    return what + "turn the flange about its axis (joint 6) and tilt the wrist (joint 5) between poses"


class RestDetector:
    """Averages joint states while every joint is slower than ``rest_velocity`` [rad/s]; a rest
    of at least ``rest_time`` [s] becomes a sample, one per distinct pose (a pose within
    ``same_pose`` [rad] of an earlier one replaces it).

    ``friction`` (the model's JointFriction, or None): its torque at each joint state's
    measured velocity is taken off that state's efforts before averaging. Inside the rest band
    the tanh-smoothed Coulomb friction is not small (with the default smoothing velocity, 76 %
    of its level at 0.01 rad/s, 96 % at 0.02); at qd = 0 it is exactly 0. A rest whose joint states carry no effort
    is no sample; its pose is counted in ``without_effort`` (until a sample of it comes)."""

    def __init__(
        self,
        rest_velocity: float,
        rest_time: float,
        same_pose: float = 1e-3,
        max_samples: int = 100,
        friction: JointFriction | None = None,
    ):
        self.rest_velocity, self.rest_time = rest_velocity, rest_time
        self.same_pose, self.max_samples = same_pose, max_samples
        self.friction = friction
        self.samples: list[RestSample] = []
        self.without_effort: list[np.ndarray] = []  # poses of rests without effort
        self._restart()

    def clear(self) -> None:
        self.samples, self.without_effort = [], []
        self._restart()

    def _restart(self) -> None:
        self._start = self._last = None  # times of the current rest's first and last joint states
        self._sum_q = self._sum_effort = self._sum_squares = None
        self._count = 0
        self._has_effort = True  # of the current rest's joint states (a change ends the rest)

    def update(self, t: float, q, qd, effort) -> bool:
        """Take one joint state (effort may be None); True when a rest sample was added.
        ValueError, nothing taken, for an effort too large to average (its square overflows)."""
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        if effort is not None:
            effort = np.asarray(effort, dtype=float)
            with np.errstate(over="ignore", invalid="ignore"):
                if not np.isfinite(effort * effort).all():
                    raise ValueError(f"effort {effort.tolist()} N m: too large to average")
        moving = np.max(np.abs(qd)) >= self.rest_velocity
        added = False
        if moving or (self._start is not None and self._has_effort != (effort is not None)):
            added = self._close()
            self._restart()
        if moving:
            return added
        if self._start is None:
            self._start, self._has_effort = t, effort is not None
            self._sum_q, self._sum_effort, self._sum_squares = (np.zeros_like(q) for _ in range(3))
        self._sum_q += q
        if effort is not None:
            if self.friction is not None:
                effort = effort - self.friction.torques(qd)
            self._sum_effort += effort
            self._sum_squares += effort**2
        self._count += 1
        self._last = t
        return added

    def _close(self) -> bool:
        if self._start is None or self._last - self._start < self.rest_time:
            return False
        n = self._count
        q = self._sum_q / n
        if not self._has_effort:
            self.without_effort = self._others(self.without_effort, q, lambda p: p) + [q]
            return False
        mean = self._sum_effort / n
        error = None
        if n > 1:
            variance = np.maximum(self._sum_squares / n - mean**2, 0.0) * n / (n - 1)
            error = np.sqrt(variance / n)
        self.samples = self._others(self.samples, q, lambda s: s.q) + [RestSample(q, mean, n, error)]
        self.without_effort = self._others(self.without_effort, q, lambda p: p)
        return True

    def _others(self, kept: list, q: np.ndarray, pose_of) -> list:
        """``kept`` without the entries of pose q, leaving room for one more (at most max_samples)."""
        others = [x for x in kept if np.max(np.abs(pose_of(x) - q)) > self.same_pose]
        return others[len(others) - self.max_samples + 1 :] if len(others) >= self.max_samples else others

    def flush(self) -> bool:
        """Close a rest still going on (e.g. before an estimate): True if it became a sample."""
        added = self._close()
        if added:
            self._restart()
        return added
