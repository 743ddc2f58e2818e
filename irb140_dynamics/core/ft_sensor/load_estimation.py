"""The sensor's bias and the tool's mass and centre of mass from readings at rest.

At rest the tool loads the sensor with its weight alone. With g_s = R^T g, gravity in the
sensor's axes (R the sensor's orientation at the pose), and the mount (R_m, p_m: the sensor
frame in the flange frame), a reading is linear in the ten unknowns
x = [b_f (3), b_tau (3), m, h (3)], h = m c the tool's first moment (c in the flange frame):

    f   = b_f + m g_s
    tau = b_tau + (R_m^T (c - p_m)) x m g_s = b_tau + [g_s]x R_m^T p_m m - [g_s]x R_m^T h

Least squares over the rest poses gives x, its standard deviations from the residual, and
the condition number of the regressor with its columns scaled to unit norm. A turn about
gravity leaves g_s as it was: the poses must hold the sensor in at least MIN_ORIENTATIONS
orientations relative to gravity (three distinct directions of g_s always determine x).

Refusals (EstimationError, one line saying what to do): no gravity, fewer orientations, poses too
similar (condition above MAX_CONDITION), a mass below zero by more than 3 standard
deviations and NEGATIVE_MASS (readings of the opposite sign, the wrench on the tool rather
than the tool's on the sensor, or of other axes than the sensor link's). A tool too light to tell from the noise (mass
not above 3 standard deviations) gives the bias and no CoM (``com`` None).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.kinematics import flange_pose
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.payload.mass_com_estimation import EstimationError, RestSample

MIN_ORIENTATIONS = 3
DISTINCT_ANGLE = 0.05  # rad between two directions of gravity in the sensor's axes
MAX_CONDITION = 1e3
NEGATIVE_MASS = 0.01  # kg: a mass further below zero (and below 3 standard deviations) is refused


@dataclass(frozen=True)
class FtLoadEstimate:
    bias: np.ndarray  # (6,) N, N m: the reading of a sensor carrying nothing
    mass: float  # kg
    com: tuple[float, float, float] | None  # m, flange frame; None: the tool too light to place it
    mass_std: float
    com_std: tuple[float, float, float] | None
    residual_rms: tuple[float, float]  # N, N m: of the forces and the torques
    poses: int
    condition: float

    def summary(self) -> str:
        b = ", ".join(f"{x:.3f}" for x in self.bias)
        text = f"bias ({b}) N, N m; tool {self.mass:.3f} +- {self.mass_std:.3f} kg"
        if self.com is None:
            text += ", too light to place its centre of mass"
        else:
            c, s = self.com, self.com_std
            text += f" at ({c[0]:.4f}, {c[1]:.4f}, {c[2]:.4f}) +- ({s[0]:.4f}, {s[1]:.4f}, {s[2]:.4f}) m"
        f, t = self.residual_rms
        return f"{text}; residual RMS {f:.3f} N, {t:.4f} N m; {self.poses} poses; condition {self.condition:.1f}"


def gravity_in_sensor(model: RobotModel, q, mount: np.ndarray) -> np.ndarray:
    """g in the sensor's axes at pose q [m/s^2]."""
    R = flange_pose(model, q)[:3, :3] @ mount[:3, :3]
    return R.T @ np.asarray(model.gravity)


def load_columns(g_s: np.ndarray, mount: np.ndarray) -> np.ndarray:
    """The 6 x 10 regressor of one rest pose (see the module)."""
    skew = np.array([[0.0, -g_s[2], g_s[1]], [g_s[2], 0.0, -g_s[0]], [-g_s[1], g_s[0], 0.0]])
    R_m, p_m = mount[:3, :3], mount[:3, 3]
    Y = np.zeros((6, 10))
    Y[:3, :3], Y[3:, 3:6] = np.eye(3), np.eye(3)
    Y[:3, 6], Y[3:, 6] = g_s, skew @ R_m.T @ p_m
    Y[3:, 7:] = -skew @ R_m.T
    return Y


def estimate_ft_load(model: RobotModel, samples: list[RestSample], mount: np.ndarray | None = None) -> FtLoadEstimate:
    """Bias, mass and CoM from rest samples (``effort``: the mean reading, 6 numbers), or
    EstimationError (see the module)."""
    mount = np.eye(4) if mount is None else mount
    if not np.any(model.gravity):
        raise EstimationError("the model's gravity is zero: a tool's load shows at rest only under gravity")
    gravities = [gravity_in_sensor(model, s.q, mount) for s in samples]
    if _orientations(gravities) < MIN_ORIENTATIONS:
        raise EstimationError(
            f"the sensor rested in {_orientations(gravities)} orientation(s) relative to gravity, at least "
            f"{MIN_ORIENTATIONS} needed: stop the arm in more poses that tilt the wrist differently"
        )
    Y = np.vstack([load_columns(g, mount) for g in gravities])
    b = np.concatenate([np.asarray(s.effort, dtype=float) for s in samples])
    weights = np.ones(b.size)
    for _ in range(2):  # unweighted, then forces and torques weighted by their residuals' RMS
        x, condition, covariance = _least_squares(Y * weights[:, None], b * weights)
        residual = (b - Y @ x).reshape(-1, 6)
        rms = (float(np.sqrt(np.mean(residual[:, :3] ** 2))), float(np.sqrt(np.mean(residual[:, 3:] ** 2))))
        weights = np.tile(np.repeat([1.0 / (rms[0] or 1.0), 1.0 / (rms[1] or 1.0)], 3), len(samples))
    std = np.sqrt(np.maximum(np.diag(covariance), 0.0))
    mass, h = float(x[6]), x[7:]
    if mass < -max(3.0 * std[6], NEGATIVE_MASS):
        raise EstimationError(
            f"the tool's mass came out negative ({mass:.3f} +- {std[6]:.3f} kg): the readings must be the wrench "
            "on the sensor from the tool (a hanging tool reads its weight), in ft_sensor.link's axes"
        )
    com = com_std = None
    if mass > 3.0 * std[6]:
        com = tuple(float(v) for v in h / mass)
        # first order: dc = (dh - c dm) / m
        J = np.zeros((3, 10))
        J[:, 7:], J[:, 6] = np.eye(3) / mass, -np.array(com) / mass
        com_std = tuple(float(v) for v in np.sqrt(np.maximum(np.diag(J @ covariance @ J.T), 0.0)))
    return FtLoadEstimate(x[:6].copy(), mass, com, float(std[6]), com_std, rms, len(samples), float(condition))


def _least_squares(Y: np.ndarray, b: np.ndarray):
    """(x, condition, covariance of x) of Y x = b, columns scaled to unit norm;
    EstimationError when the condition exceeds MAX_CONDITION."""
    scale = np.linalg.norm(Y, axis=0)
    U, sigma, Vt = np.linalg.svd(Y / scale, full_matrices=False)
    condition = sigma[0] / sigma[-1] if sigma[-1] > 0 else math.inf
    if condition > MAX_CONDITION:
        raise EstimationError(
            f"the rest poses are too similar (condition number {condition:.3g}): tilt the wrist further between them"
        )
    x = (Vt.T @ ((U.T @ b) / sigma)) / scale
    residual = b - Y @ x
    variance = float(residual @ residual) / max(b.size - x.size, 1)
    covariance = variance * ((Vt.T / sigma**2) @ Vt) / np.outer(scale, scale)
    return x, float(condition), covariance


def _orientations(gravities: list[np.ndarray]) -> int:
    """How many directions of gravity, DISTINCT_ANGLE apart, the poses give."""
    distinct: list[np.ndarray] = []
    for g in gravities:
        norm = np.linalg.norm(g)
        if norm == 0.0:
            continue
        u = g / norm
        if all(math.acos(min(1.0, float(u @ v))) > DISTINCT_ANGLE for v in distinct):
            distinct.append(u)
    return len(distinct)
