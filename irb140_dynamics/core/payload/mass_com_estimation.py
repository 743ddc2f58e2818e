"""What is on the flange: the payload's mass and centre of mass from efforts at rest.

At rest the measured efforts hold the arm and the payload against gravity. The payload's
part is linear in phi = [m, m c_x, m c_y, m c_z] (c in the flange frame):

    effort - g_arm(q) = Y(q) phi,   Y = [-J_v^T g,  -J_w^T (R e_k x g) for k = x, y, z]

with J_v, J_w the flange Jacobian's rows, R the flange orientation and g the gravity
vector, all in the base frame (g_arm: the model's own gravity torques, payload removed).
Weighted least squares over the rest poses (``rest_samples`` keeps them from a stream of
joint states; each torque weighted by the inverse of its average's standard error, when
the rest had several joint states) gives phi, its standard deviations from the residual,
and the condition number of the (column-scaled) weighted Y.

The payload's inertia does not show at rest: it is not estimated.

Refusals (EstimationError, saying what to do): fewer than MIN_POSES poses; poses too
similar to determine phi (condition number above MAX_CONDITION: the message says which
line of the CoM is undetermined and which wrist motion would help); an implausible result
(mass <= 0, or the CoM more than MAX_COM_DISTANCE from the flange).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.dynamics import gravity
from irb140_dynamics.core.kinematics import flange_jacobian, flange_pose
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
