"""A physically consistent full parameter set: closest to the data, regularised to a prior.

Each link's ten inertial parameters are written through its pseudo-inertia (Wensing,
Kim, Slotine 2017)

    J = [[S, h], [h^T, m]],   S = tr(I)/2 1 - I  (I about the joint frame's origin),

which is positive definite exactly when the link is a physical body (m > 0, inertia about
the CoM positive and obeying the triangle inequality). The log-Cholesky parameterisation
(Rucker & Wensing 2022) J = U U^T,

    U = e^alpha [[e^d1, s12, s13, t1], [0, e^d2, s23, t2], [0, 0, e^d3, t3], [0, 0, 0, 1]],

maps any ten real numbers to such a J and back, so an unconstrained solver stays within
physical bodies. Friction and armature are bounded below by 0. SciPy's least_squares
(trust region reflective) minimises the maximum a posteriori cost

    | L^T (K pi - beta_hat) |^2  +  weight | (pi - pi_prior) / s |^2

L L^T the inverse covariance of the weighted least-squares base parameters beta_hat (so
the first term is in their standard deviations), s the prior's spread: per link, with
m_ref = max(its mass, 10 % of the mean link mass) and l a length scale of the arm (the
mean joint-to-joint distance, at least 0.1 m), 50 % of m_ref for the mass, of m_ref l for
each first moment, of m_ref l^2 for each inertia entry; 10 N m s/rad, 10 N m and
1 kg m^2 for viscous friction, Coulomb friction and armature. The data decide every
combination they see; the prior settles what they do not (and a link's massless-ness).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.regressor import (
    INERTIAL_PARAMETERS,
    JOINT_TERMS,
    PARAMETERS_PER_JOINT,
    inertial_parameters,
    with_inertial_parameters,
    zero_parameters,
)
from irb140_dynamics.identification.base import BaseParameters
from irb140_dynamics.identification.least_squares import Estimate

PRIOR_SPREAD = 0.5
FRICTION_SPREAD = (10.0, 10.0, 1.0)  # viscous N m s/rad, Coulomb N m, armature kg m^2
_EXCHANGE = np.eye(4)[::-1]
MAX_EVALUATIONS = 500  # an estimate far outside the physical set creeps toward its boundary: stop there
# bounds of the log-Cholesky numbers, far beyond any arm, that keep the solver from overflow:
# mass e^(2 alpha) up to 1e6 kg (the model's cap), CoM and spreads up to 30 m
THETA_LOWER = np.array([-30.0, -30.0, -30.0, -30.0, -30.0, -30.0, -30.0, -30.0, -30.0, -30.0])
THETA_UPPER = np.array([np.log(1e6) / 2, 3.5, 3.5, 3.5, 30.0, 30.0, 30.0, 30.0, 30.0, 30.0])


def pseudo_inertia(pi10) -> np.ndarray:
    """J (4 x 4) of ten parameters [m, mcx, mcy, mcz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]."""
    m, hx, hy, hz, xx, xy, yy, xz, yz, zz = pi10
    I = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    J = np.empty((4, 4))
    J[:3, :3] = np.trace(I) / 2.0 * np.eye(3) - I
    J[:3, 3] = J[3, :3] = hx, hy, hz
    J[3, 3] = m
    return J


def parameters_of(J: np.ndarray) -> np.ndarray:
    """The ten parameters of a pseudo-inertia."""
    S = J[:3, :3]
    I = np.trace(S) * np.eye(3) - S
    return np.array([J[3, 3], *J[:3, 3], I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]])


def log_cholesky(theta) -> np.ndarray:
    """J = U U^T of the ten log-Cholesky numbers [alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3]."""
    U = _upper(theta)
    return U @ U.T


def _upper(theta) -> np.ndarray:
    alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3 = theta
    return np.exp(alpha) * np.array(
        [[np.exp(d1), s12, s13, t1], [0.0, np.exp(d2), s23, t2], [0.0, 0.0, np.exp(d3), t3], [0.0, 0.0, 0.0, 1.0]]
    )


_ENTRIES = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))  # of d1..d3, s12, s23, s13, t1..t3


_ROWS, _COLUMNS = np.array(_ENTRIES).T


def parameters_and_jacobian(theta) -> tuple[np.ndarray, np.ndarray]:
    """The ten parameters of log_cholesky(theta) and their derivatives (10 x 10) by theta."""
    pi10, jacobian = parameters_and_jacobians(np.asarray(theta, dtype=float)[None])
    return pi10[0], jacobian[0]


def parameters_and_jacobians(thetas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``parameters_and_jacobian`` of each row of thetas (L, 10): (L, 10), (L, 10, 10)."""
    L = len(thetas)
    alpha, d, s, t = thetas[:, 0], thetas[:, 1:4], thetas[:, 4:7], thetas[:, 7:]
    U = np.zeros((L, 4, 4))
    U[:, [0, 1, 2], [0, 1, 2]], U[:, [0, 1, 0], [1, 2, 2]], U[:, :3, 3], U[:, 3, 3] = np.exp(d), s, t, 1.0
    U *= np.exp(alpha)[:, None, None]
    derivatives = np.zeros((L, 10, 4, 4))
    derivatives[:, 0] = U  # d U / d alpha
    k = np.arange(9)
    # d e^(alpha + d) / dd; d (e^alpha s) / ds
    derivatives[:, 1 + k, _ROWS, _COLUMNS] = np.where(k < 3, U[:, _ROWS, _COLUMNS], np.exp(alpha)[:, None])
    Ut = U.transpose(0, 2, 1)
    products = derivatives @ Ut[:, None]
    jacobian = _parameters_of_many((products + products.transpose(0, 1, 3, 2)).reshape(-1, 4, 4))
    return _parameters_of_many(U @ Ut), jacobian.reshape(L, 10, 10).transpose(0, 2, 1)


def _parameters_of_many(J: np.ndarray) -> np.ndarray:
    """``parameters_of`` of each pseudo-inertia of J (K, 4, 4): (K, 10)."""
    S = J[:, :3, :3]
    trace = np.trace(S, axis1=1, axis2=2)
    I = trace[:, None, None] * np.eye(3) - S
    return np.column_stack([J[:, 3, 3], J[:, :3, 3], I[:, (0, 0, 1, 0, 1, 2), (0, 1, 1, 2, 2, 2)]])  # Ixx ... Izz


def log_cholesky_of(J: np.ndarray) -> np.ndarray:
    """The log-Cholesky numbers of a positive definite J (inverse of ``log_cholesky``)."""
    U = _EXCHANGE @ np.linalg.cholesky(_EXCHANGE @ J @ _EXCHANGE) @ _EXCHANGE  # upper triangular, U U^T = J
    scale = U[3, 3]
    V = U / scale
    return np.array([np.log(scale), *np.log(np.diag(V)[:3]), V[0, 1], V[1, 2], V[0, 2], *V[:3, 3]])


def is_consistent(pi: np.ndarray, n: int, tolerance: float = 1e-9) -> bool:
    """Every link's pseudo-inertia positive semidefinite, friction and armature >= 0."""
    for i in range(n):
        J = pseudo_inertia(pi[_link(i)])
        eigenvalues = np.linalg.eigvalsh(J)
        if eigenvalues[0] < -tolerance * max(1.0, eigenvalues[-1]):
            return False
    return bool(np.all(pi[INERTIAL_PARAMETERS * n :] >= 0.0))


def _link(i: int) -> slice:
    """Link i's inertial parameters in pi."""
    return slice(INERTIAL_PARAMETERS * i, INERTIAL_PARAMETERS * (i + 1))


def prior_spread(model: RobotModel, pi_prior: np.ndarray) -> np.ndarray:
    """s of the module's docstring, (13 n_all,): per joint of ``model.joints``."""
    n = len(model.joints)
    masses = pi_prior[0 : INERTIAL_PARAMETERS * n : INERTIAL_PARAMETERS]
    reference = np.maximum(masses, 0.1 * max(masses.mean(), 1e-3))
    distances = [np.linalg.norm(np.add(j.pre.xyz, j.post.xyz)) for j in model.joints]
    length = max(0.1, float(np.mean(distances)))
    per_link = np.array([1.0, length, length, length] + [length**2] * 6)
    links = PRIOR_SPREAD * np.outer(reference, per_link).ravel()
    return np.concatenate([links, np.tile(FRICTION_SPREAD, n)])


@dataclass(frozen=True, eq=False)
class ConsistentFit:
    pi: np.ndarray  # (13 n,)
    model: RobotModel
    deviation: np.ndarray  # (K pi - beta_hat) / std, per base parameter
    consistent: bool
    misfit: float = 0.0  # | L^T (K pi - beta_hat) |^2: the data's chi-square of pi


def consistent_parameters(
    prior: RobotModel,
    base: BaseParameters,
    estimate: Estimate,
    prior_weight: float = 1.0,
    max_evaluations: int = MAX_EVALUATIONS,
    start: np.ndarray | None = None,
) -> ConsistentFit:
    """The physically consistent parameters of the module's docstring, as a model (a
    mimic joint's link is a link: n counts every joint of ``prior.joints``)."""
    n = len(prior.joints)
    size, joints = PARAMETERS_PER_JOINT * n, INERTIAL_PARAMETERS * n
    # the solver's unknowns: every entry but those no model of the structure holds (zero,
    # see core.regressor: a mimic joint's Coulomb friction of multiplier other than +-1)
    free = np.setdiff1d(np.arange(size), zero_parameters(prior))
    pi_prior = inertial_parameters(prior)
    spread = prior_spread(prior, pi_prior)
    K = base.matrix()
    root = np.linalg.cholesky(estimate.information())  # L: L L^T = covariance^-1
    data_map = root.T @ K
    data_target = root.T @ estimate.beta
    regularisation = np.sqrt(prior_weight) / spread

    def evaluate(unknowns):
        """pi(x) and d pi / d x (block diagonal: links, then the identity for friction), x
        every entry (the unknowns, zeros elsewhere); the derivatives by the unknowns."""
        x = np.zeros(size)
        x[free] = unknowns
        pi, jacobian = np.empty(size), np.zeros((size, size))
        links, derivatives = parameters_and_jacobians(x[:joints].reshape(n, INERTIAL_PARAMETERS))
        pi[:joints] = links.ravel()
        for i in range(n):
            jacobian[_link(i), _link(i)] = derivatives[i]
        pi[joints:] = x[joints:]
        jacobian[joints:, joints:] = np.eye(JOINT_TERMS * n)
        return pi, jacobian[:, free]

    def residuals(x):
        pi, _ = evaluate(x)
        return np.concatenate([data_map @ pi - data_target, regularisation * (pi - pi_prior)])

    def jacobian(x):
        _, dpi = evaluate(x)
        return np.vstack([data_map @ dpi, regularisation[:, None] * dpi])

    # start: the unconstrained optimum (a linear least-squares problem), each link's
    # pseudo-inertia's eigenvalues raised to a small floor, friction and armature to 0
    # (or ``start``, a full parameter set: e.g. another fit's)
    if start is None:
        normal = data_map.T @ data_map + np.diag(regularisation**2)
        unconstrained = np.linalg.solve(normal, data_map.T @ data_target + regularisation**2 * pi_prior)
    else:
        unconstrained = np.asarray(start, dtype=float)
    start = [
        log_cholesky_of(nearest_positive(pseudo_inertia(unconstrained[_link(i)]), spread[_link(i)])) for i in range(n)
    ]
    x0 = np.concatenate([*start, np.maximum(unconstrained[INERTIAL_PARAMETERS * n :], 0.0)])
    lower = np.concatenate([np.tile(THETA_LOWER, n), np.zeros(JOINT_TERMS * n)])
    upper = np.concatenate([np.tile(THETA_UPPER, n), np.full(JOINT_TERMS * n, np.inf)])
    x0 = np.clip(x0, lower, upper)[free]
    result = least_squares(
        residuals,
        x0,
        jac=jacobian,
        bounds=(lower[free], upper[free]),
        method="trf",
        x_scale="jac",
        max_nfev=max_evaluations,
        ftol=1e-4,
    )
    pi, _ = evaluate(result.x)
    pi[joints:] = np.maximum(pi[joints:], 0.0)
    deviation = (K @ pi - estimate.beta) / estimate.std
    misfit = float(np.sum((data_map @ pi - data_target) ** 2))
    model = with_inertial_parameters(prior, pi)
    return ConsistentFit(pi, model, deviation, is_consistent(pi, n), misfit)


@dataclass(frozen=True)
class PhysicalCheck:
    """Is there a physical arm the estimate's uncertainty allows? chi2: the squared distance,
    in the estimate's covariance, from the estimate to the nearest physical arm (a fit
    with a vanishing pull to the prior); bound: the chi-square quantile PHYSICAL_CONFIDENCE
    for r base parameters. The true arm's own chi2 is below the bound with that
    probability, and the nearest arm's is smaller than the true one's: a chi2 beyond the
    bound says no rigid arm explains the data, whatever the noise drew."""

    chi2: float
    bound: float
    base_parameters: int

    @property
    def physical(self) -> bool:
        return self.chi2 <= self.bound


PHYSICAL_CONFIDENCE = 0.999
NEAREST_WEIGHT = 1e-6  # the pull to the prior that only settles what the data do not see


def physical_check(prior: RobotModel, base: BaseParameters, estimate: Estimate, fit: ConsistentFit) -> PhysicalCheck:
    """The PhysicalCheck of an estimate, starting the search for the nearest arm at ``fit``."""
    from scipy.special import gammaincinv

    nearest = consistent_parameters(prior, base, estimate, NEAREST_WEIGHT, start=fit.pi)
    chi2 = min(nearest.misfit, fit.misfit)
    r = base.count
    return PhysicalCheck(chi2, float(2.0 * gammaincinv(r / 2.0, PHYSICAL_CONFIDENCE)), r)


def nearest_positive(J: np.ndarray, spread10: np.ndarray) -> np.ndarray:
    """J with its eigenvalues raised to at least those of a small body at the origin
    (1e-3 of the spread's mass, of its length scale)."""
    mass, length2 = spread10[0] * 1e-3, spread10[4] / spread10[0]
    floor = mass * min(length2, 1.0)
    eigenvalues, vectors = np.linalg.eigh((J + J.T) / 2.0)
    return (vectors * np.maximum(eigenvalues, floor)) @ vectors.T
