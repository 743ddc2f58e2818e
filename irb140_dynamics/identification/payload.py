"""Load identification: a payload's mass, centre of mass and inertia from a recording of the
arm carrying it, the arm's own parameters known.

The arm's torques are linear in its parameters (``core.regressor``): with the payload's ten
inertial parameters phi in the flange frame ([m, m c_x, m c_y, m c_z, Ixx, Ixy, Iyy, Ixz,
Iyz, Izz], the inertia about the flange's origin, as ``core.regressor`` orders a link's),

    tau - tau_arm(q, qd, qdd) = Y_last(q, qd, qdd) T phi

tau_arm the arm without payload (links, friction, rotor inertia of its params file),
Y_last the last link's ten regressor columns and T the linear map of a body's parameters
from the flange frame to the last joint's frame (``flange_map``). Every fit point's rows
are summed into normal equations (``least_squares``): a moving joint's row where it is fast
enough for the Coulomb model (as ``identify`` uses rows), and every row of a joint held
still throughout (it carries the payload's static load). Weighted least squares gives
phi_hat and its covariance, scaled by the measured correlation of its residuals as
``identify`` scales it (``correlation``: torques the arm's own model leaves unexplained
change slowly and tell less than as many independent samples). The recording is refused,
naming the parameters, when it does not excite one: its column (in units of a 1 kg body 0.1 m out) vanishes to rounding or
lies in the others' span (``excitation``), or its standard deviation exceeds
MAX_RELATIVE_STD of the payload's own scale (m, m L, m L^2; see ``_check_excitation``);
and when its mass comes out negative beyond the noise (``_check_mass``), or when the efforts
are a multiple of the torques the arm's model gives (``_check_effort_scale``: tau = s
tau_arm + Y_last T phi fitted with s free, s away from 1 beyond MAX_EFFORT_SCALE_ERROR and
the noise: efforts not in N m, where phi would absorb (s - 1) tau_arm, 37 t for 3.5 kg in
N mm). The payload is then the physical body closest to phi_hat in its covariance's metric:
phi = phi(theta) through the log-Cholesky pseudo-inertia of ``consistent`` (mass > 0,
inertia about the CoM positive definite, triangle inequality hold for any theta), so a
phi_hat that is physical is kept as it is.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np
from scipy.optimize import least_squares

from irb140_dynamics.core.model.joints import Placement
from irb140_dynamics.core.model.rigid_body import RigidBody
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.regressor import (
    LINK_PARAMETERS,
    body_parameters,
    inertial_parameters,
    parameters_body,
    regressor_batch,
)
from irb140_dynamics.identification.base import BaseParameters
from irb140_dynamics.identification.consistent import (
    log_cholesky_of,
    nearest_positive,
    parameters_and_jacobian,
    pseudo_inertia,
)
from irb140_dynamics.identification.correlation import correlation_factor
from irb140_dynamics.identification.least_squares import Estimate, NormalEquations, weighted_least_squares
from irb140_dynamics.identification.pipeline import (
    FIT_BATCH,
    SLOW_SPEEDS,
    IdentificationSettings,
    Progress,
    SampleTally,
    nothing_usable,
    read_fit_points,
)
from irb140_dynamics.identification.recording import Recording, RecordingError
from irb140_dynamics.identification.selection import rows_used, select

MIN_EXCITATION = 1e-6  # sine of the angle between a parameter's column and the others' span: rounding
WEAK_EXCITATION = 1e-3  # named (with the least excited) when the regressor is singular
MAX_RELATIVE_STD = 0.05  # of the payload's own scale (see _check_excitation)
MIN_MASS = 0.1  # kg
NEGATIVE_MASS_SIGMAS = 5.0  # a mass estimate below -5 standard deviations: no payload (see _check_mass)
MAX_EFFORT_SCALE_ERROR = 0.05  # the efforts / the arm model's torques, beyond 1 +- this: refused
EFFORT_SCALE_SIGMAS = 5.0  # ... and beyond this many standard deviations of that ratio
MIN_LENGTH = 0.1  # m
UNIT_SCALE = np.array([1.0, 0.1, 0.1, 0.1, 0.01, 0.01, 0.01, 0.01, 0.01, 0.01])  # 1 kg, 0.1 m out
PARAMETER_LABELS = ("mass", "m*cx", "m*cy", "m*cz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")  # phi's, as printed
_ALL_INDEPENDENT = BaseParameters(tuple(LINK_PARAMETERS), np.arange(10), np.arange(0), np.zeros((10, 0)), np.arange(0))
_WITH_SCALE = BaseParameters((*LINK_PARAMETERS, "s"), np.arange(11), np.arange(0), np.zeros((11, 0)), np.arange(0))


def _moved(pi10: np.ndarray, R: np.ndarray, p: np.ndarray) -> np.ndarray:
    """A body's ten parameters in frame F, in the frame where x' = R x + p."""
    m, hx, hy, hz, xx, xy, yy, xz, yz, zz = pi10
    I = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    h = R @ np.array([hx, hy, hz])
    cross = 2.0 * (h @ p) * np.eye(3) - np.outer(h, p) - np.outer(p, h)
    I = R @ I @ R.T + cross + m * (p @ p * np.eye(3) - np.outer(p, p))
    return np.array([m, *(h + m * p), I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]])


def flange_map(model: RobotModel) -> np.ndarray:
    """T (10 x 10): a payload's parameters in the flange frame -> in the last joint's frame."""
    post = model.joints[-1].post
    R_post, R_flange = post.rotation(), model.flange.rotation()
    R = R_post @ R_flange
    p = R_post @ np.asarray(model.flange.xyz, dtype=float) + np.asarray(post.xyz, dtype=float)
    return np.column_stack([_moved(e, R, p) for e in np.eye(10)])


def payload_regressor(arm: RobotModel, Q, QD, QDD) -> tuple[np.ndarray, np.ndarray]:
    """(Y_p (N, n, 10), tau_arm (N, n)): the payload's regressor in the flange frame and the
    torques of the arm without its payload (friction and rotor inertia included)."""
    free, theta, T = _regressor_constants(arm)
    n = arm.n
    Y = regressor_batch(free, Q, QD, QDD)
    tau_arm = Y @ theta
    return Y[:, :, 10 * (n - 1) : 10 * n] @ T, tau_arm


@lru_cache(maxsize=16)
def _regressor_constants(arm: RobotModel) -> tuple[RobotModel, np.ndarray, np.ndarray]:
    """(the arm without payload, its inertial parameters, ``flange_map``): the same for every
    batch of one arm (a design evaluates hundreds)."""
    free = arm.with_payload(RigidBody())
    return free, inertial_parameters(free), flange_map(arm)


def payload_parameters(payload: RigidBody) -> np.ndarray:
    """phi (10,) of a payload given as the params file gives it (flange frame, about its CoM)."""
    return body_parameters(payload, Placement())


def payload_of(phi) -> RigidBody:
    """The payload (mass, CoM, inertia about the CoM in flange axes) of phi; ModelError if none."""
    return parameters_body("payload", phi, Placement())


def excitation(information: np.ndarray) -> np.ndarray:
    """Per parameter, the sine of the angle between its (weighted) regressor column and the
    span of the others': 1 / sqrt(N_jj (N^-1)_jj) of the normal matrix N; 0 when unseen
    (its column's norm below MIN_EXCITATION of the largest: rounding)."""
    diagonal = np.diag(information).copy()
    seen = diagonal > MIN_EXCITATION**2 * max(float(diagonal.max()), 0.0)
    out = np.zeros(len(diagonal))
    if not seen.any():
        return out
    scale = 1.0 / np.sqrt(diagonal[seen])
    C = information[np.ix_(seen, seen)] * np.outer(scale, scale)
    eigenvalues, vectors = np.linalg.eigh((C + C.T) / 2.0)
    inverse_diagonal = (vectors**2) @ (1.0 / np.maximum(eigenvalues, 1e-300))
    out[seen] = 1.0 / np.sqrt(inverse_diagonal)
    return out


@dataclass(frozen=True, eq=False)
class PayloadFit:
    payload: RigidBody  # the physical payload closest to the estimate
    phi: np.ndarray  # (10,) its parameters, flange frame
    estimate: Estimate  # phi_hat: weighted least squares, unconstrained
    excitation: np.ndarray  # (10,) see ``excitation``
    std: dict  # "mass" float, "com" (3,), "inertia" (6,): standard deviations (delta method)
    tally: SampleTally
    rows: np.ndarray  # (n,) torque rows used per joint
    residual_rms: np.ndarray  # (n,) N m, of the fitted payload, per joint
    peak: np.ndarray  # (n,) N m: largest |tau - tau_arm| per joint among the rows used
    misfit: float  # | L^T (phi - phi_hat) |^2: 0 when phi_hat is physical


def fit_payload(
    arm: RobotModel,
    path,
    settings: IdentificationSettings | None = None,
    progress: Progress | None = None,
) -> PayloadFit:
    """The payload of ``arm`` (its own parameters known) from the recording at ``path``.
    RecordingError (one line) when the recording is unusable or leaves a parameter unexcited."""
    settings = settings or IdentificationSettings()
    recording = Recording(path, arm.joint_names, settings.topic, settings.chunk_size)
    tally, points = read_fit_points(arm, recording, settings, progress)
    min_speed = settings.min_speed if settings.min_speed is not None else SLOW_SPEEDS * arm.smoothing_velocity
    if points is not None and len(points):
        half_window = tally.design.half / tally.design.rate
        fast = rows_used(points.qd, points.qdd, min_speed, half_window)
        tally.selection = select(fast.any(axis=1))
    if points is None or not len(points) or tally.selection is None:
        raise RecordingError(tally.path, nothing_usable(tally, "to fit", min_speed))
    span = tally.selection.train
    points, fast = points.take(span), fast[span]
    use = fast | ~fast.any(axis=0)  # a joint held still throughout: all its rows
    with_scale = NormalEquations(arm.n, 11)  # the payload's ten columns, then the arm's torques
    for start in range(0, len(points), FIT_BATCH):
        batch = points.take(slice(start, start + FIT_BATCH))
        Y, tau_arm = payload_regressor(arm, batch.q, batch.qd, batch.qdd)
        with_scale.add(
            np.concatenate([Y, tau_arm[..., None]], axis=2), batch.tau - tau_arm, use[start : start + FIT_BATCH]
        )
    equations = _payload_columns(with_scale)
    filter_correlation = tally.design.noise_correlation()
    estimate = _estimate(tally.path, equations, filter_correlation)
    first = points.take(slice(0, settings.correlation_points))  # consecutive fit points: their residuals
    Y, tau_arm = payload_regressor(arm, first.q, first.qd, first.qdd)
    residuals = Y @ estimate.beta - (first.tau - tau_arm)
    correlation, _ = correlation_factor(np.where(use[: len(first)], residuals, np.nan), filter_correlation)
    estimate = replace(estimate, covariance=estimate.covariance * (correlation / filter_correlation))
    _check_mass(tally.path, estimate)
    _check_effort_scale(tally.path, with_scale, filter_correlation)  # the first cause: efforts not in N m
    _check_excitation(tally.path, estimate)
    phi, misfit = _nearest_physical(estimate)
    return PayloadFit(
        payload_of(phi),
        phi,
        estimate,
        excitation(estimate.information()),
        _standard_deviations(phi, estimate.covariance),
        tally,
        equations.rows.copy(),
        equations.rms(phi),
        equations.peak.copy(),
        misfit,
    )


def _scaled(equations: NormalEquations) -> NormalEquations:
    """The sums for phi / UNIT_SCALE: regressor columns of like size."""
    scaled = NormalEquations(*equations.b.shape)
    scaled.A = equations.A * np.outer(UNIT_SCALE, UNIT_SCALE)
    scaled.b = equations.b * UNIT_SCALE
    scaled.c, scaled.rows, scaled.peak = equations.c, equations.rows, equations.peak
    return scaled


def _estimate(path, equations: NormalEquations, correlation: float) -> Estimate:
    """Weighted least squares of phi (solved for phi / UNIT_SCALE); RecordingError naming the
    parameters least told apart from the others when the regressor is singular."""
    scaled = _scaled(equations)
    seen = excitation(scaled.A.sum(axis=0))
    _refuse(path, np.flatnonzero(seen < MIN_EXCITATION))
    try:
        estimate = weighted_least_squares(scaled, _ALL_INDEPENDENT, correlation)
    except ValueError:
        weak = np.flatnonzero(seen <= max(WEAK_EXCITATION, float(seen.min())))
        _refuse(path, weak)
        raise
    covariance = estimate.covariance * np.outer(UNIT_SCALE, UNIT_SCALE)
    return replace(estimate, beta=estimate.beta * UNIT_SCALE, covariance=covariance)


def _check_mass(path, estimate: Estimate) -> None:
    """RecordingError when the torques ask for a negative mass beyond NEGATIVE_MASS_SIGMAS of
    its standard deviation: no physical payload explains them (efforts of the other sign or
    not in N m, or the arm's own parameters far off), and the nearest one would be noise."""
    mass, std = float(estimate.beta[0]), float(estimate.std[0])
    if mass < -NEGATIVE_MASS_SIGMAS * std:
        raise RecordingError(
            path,
            f"the torques give the payload a mass of {mass:.3g} +- {std:.2g} kg: no physical payload explains "
            "them; check the efforts (their sign, N m) and the arm's own parameters (`identify` it first)",
        )


def _payload_columns(with_scale: NormalEquations) -> NormalEquations:
    """The sums of the payload's ten columns alone (tau - tau_arm = Y_last T phi)."""
    equations = NormalEquations(*with_scale.b.shape[:1], 10)
    equations.A, equations.b = with_scale.A[:, :10, :10].copy(), with_scale.b[:, :10].copy()
    equations.s, equations.t = with_scale.s[:, :10].copy(), with_scale.t.copy()
    equations.c, equations.rows, equations.peak = with_scale.c.copy(), with_scale.rows.copy(), with_scale.peak.copy()
    return equations


def _check_effort_scale(path, with_scale: NormalEquations, correlation: float) -> None:
    """RecordingError when the efforts are s times the arm model's torques, s away from 1
    beyond MAX_EFFORT_SCALE_ERROR and EFFORT_SCALE_SIGMAS standard deviations (fitted with
    the payload: tau - tau_arm = (s - 1) tau_arm + Y_last T phi). A payload cannot scale
    the torques of the arm's own links: the efforts are in other units (N mm: s = 1000),
    or the arm's own parameters are far off. Without a fit (the scale not told apart from
    the payload), nothing is said here: the payload's own fit names what it misses."""
    scaled = NormalEquations(*with_scale.b.shape)
    weights = np.append(UNIT_SCALE, 1.0)
    scaled.A = with_scale.A * np.outer(weights, weights)
    scaled.b, scaled.c, scaled.rows = with_scale.b * weights, with_scale.c, with_scale.rows
    try:
        estimate = weighted_least_squares(scaled, _WITH_SCALE, correlation)
    except ValueError:
        return
    scale, std = 1.0 + float(estimate.beta[10]), float(estimate.std[10])
    if abs(scale - 1.0) > max(MAX_EFFORT_SCALE_ERROR, EFFORT_SCALE_SIGMAS * std):
        raise RecordingError(
            path,
            f"the efforts are {scale:.4g} +- {std:.2g} times the torques of the arm's model: check their units "
            "(N m, not N mm) and sign, and the arm's own parameters (`identify` it first)",
        )


def _check_excitation(path, estimate: Estimate) -> None:
    """RecordingError naming the parameters whose standard deviation exceeds MAX_RELATIVE_STD
    of the payload's own scale: m_ref = max(m, MIN_MASS) for the mass, m_ref L for the first
    moments and m_ref L^2 for the inertia, L = max(|c|, MIN_LENGTH). The deviations grow
    with the torques the arm's own model leaves unexplained (a params file without the
    arm's friction; their correlation shows them) as well as with a weak motion: the line
    names both, first (the parameters' list may be cut at the line's end)."""
    phi = estimate.beta
    mass = max(abs(phi[0]), MIN_MASS)
    length = max(float(np.linalg.norm(phi[1:4])) / mass, MIN_LENGTH)
    scale = mass * np.array([1.0, *[length] * 3, *[length**2] * 6])
    std = estimate.std
    weak = np.flatnonzero(~(std <= MAX_RELATIVE_STD * scale))
    units = ["kg"] + ["kg m"] * 3 + ["kg m^2"] * 6
    if len(weak):
        names = ", ".join(f"{PARAMETER_LABELS[k]} (+- {std[k]:.2g} {units[k]})" for k in weak)
        raise RecordingError(
            path,
            "check the arm's parameters (torques its model leaves unexplained) or record `excitation --payload` "
            f"(a weak motion): the payload's {names} deviate by more than {100 * MAX_RELATIVE_STD:g} % of its scale "
            "(flange frame, inertia about its origin)",
        )


def _refuse(path, weak) -> None:
    """RecordingError naming the ``weak`` parameters."""
    if len(weak):
        names = ", ".join(PARAMETER_LABELS[k] for k in weak)
        raise RecordingError(
            path,
            f"the motion does not excite the payload's {names} (flange frame, inertia about its origin): "
            "record `excitation --payload` (wrist motion)",
        )


def _nearest_physical(estimate: Estimate) -> tuple[np.ndarray, float]:
    """The physical phi closest to phi_hat in the metric of its covariance, and the misfit."""
    phi_hat = estimate.beta
    root = np.linalg.cholesky(estimate.information())
    mass = max(abs(phi_hat[0]), 1e-3)
    length = max(float(np.linalg.norm(phi_hat[1:4])) / mass, 0.05)
    spread = np.array([mass, *[mass * length] * 3, *[mass * length**2] * 6])
    J = pseudo_inertia(phi_hat)
    if np.linalg.eigvalsh(J)[0] > 0.0:
        return phi_hat.copy(), 0.0
    theta0 = log_cholesky_of(nearest_positive(J, spread))

    def residuals(theta):
        return root.T @ (parameters_and_jacobian(theta)[0] - phi_hat)

    def jacobian(theta):
        return root.T @ parameters_and_jacobian(theta)[1]

    result = least_squares(residuals, theta0, jac=jacobian, method="trf", x_scale="jac", max_nfev=500)
    phi = parameters_and_jacobian(result.x)[0]
    return phi, float(np.sum(residuals(result.x) ** 2))


def _described(phi: np.ndarray) -> np.ndarray:
    """[m, c_x, c_y, c_z, Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (inertia about the CoM) of phi."""
    m = phi[0]
    c = phi[1:4] / m
    xx, xy, yy, xz, yz, zz = phi[4:]
    I = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]) - m * (c @ c * np.eye(3) - np.outer(c, c))
    return np.array([m, *c, I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])


def _standard_deviations(phi: np.ndarray, covariance: np.ndarray) -> dict:
    """Standard deviations of mass, CoM and inertia about the CoM, by the delta method."""
    steps = 1e-6 * np.maximum(np.sqrt(np.diag(covariance)), 1e-9)
    G = np.column_stack(
        [(_described(phi + s * e) - _described(phi - s * e)) / (2.0 * s) for s, e in zip(steps, np.eye(10))]
    )
    std = np.sqrt(np.maximum(np.diag(G @ covariance @ G.T), 0.0))
    return {"mass": float(std[0]), "com": std[1:4], "inertia": std[4:]}
