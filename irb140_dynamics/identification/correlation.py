"""How correlated the torque residuals are: the covariance of the estimate depends on it.

Least squares' covariance s^2 (Y^T W Y)^-1 assumes each fit point's residual independent
of the next. Two things correlate them: the smoothing filter (for noise that was white
before it, known from the filter: ``FilterDesign.noise_correlation``), and what the model
does not describe (a torque sensor's drift, a lag between torque and motion, elasticity),
which on a real arm is most of the residual and changes slowly. Then there are fewer
independent observations than fit points, and the least-squares standard deviations,
taken as they are, make the data look far more certain than they are against the prior.

The integrated autocorrelation time of a residual sequence e_k (fit points in a row),

    tau = 1 + 2 sum_{l >= 1} rho(l),     rho(l) = sum_k e_k e_{k+l} / sum_k e_k^2,

summed over Geyer's initial positive sequence (pairs rho(2m) + rho(2m+1) while they are
positive), is the factor by which correlation inflates the variance of a mean, and, to
first order, of a least-squares estimate. ``correlation_factor`` takes the largest over
the joints (the estimate's certainty is limited by its least independent joint), never
less than the filter's own factor: for white measurement noise it gives that back.
"""

from __future__ import annotations

import numpy as np

MAX_LAG_FRACTION = 0.25  # of the sequence's length: beyond, the estimate of rho is noise


def integrated_autocorrelation(e: np.ndarray) -> float:
    """tau of the sequence e (see the module's docstring); 1 for fewer than 8 values."""
    e = np.asarray(e, dtype=float)
    e = e - e.mean()
    if len(e) < 8 or not np.any(e):
        return 1.0
    size = 1 << (2 * len(e) - 1).bit_length()  # zero padding: no circular wrap-around
    spectrum = np.fft.rfft(e, size)
    autocovariance = np.fft.irfft(spectrum * np.conj(spectrum), size)[: len(e)]
    rho = autocovariance / autocovariance[0]
    lags = max(2, int(len(e) * MAX_LAG_FRACTION))
    tau = -1.0  # 1 + 2 sum rho(l >= 1) = -1 + 2 sum_m (rho(2m) + rho(2m + 1)), m >= 0
    for m in range(lags // 2):
        pair = rho[2 * m] + rho[2 * m + 1]
        if pair <= 0.0:
            break
        tau += 2.0 * pair
    return max(tau, 1.0)


def correlation_factor(residuals: np.ndarray, floor: float = 1.0) -> tuple[float, np.ndarray]:
    """(the factor, each joint's tau) of residuals (K, n) of K consecutive fit points;
    joints whose column is NaN are left out (tau NaN)."""
    residuals = np.asarray(residuals, dtype=float)
    taus = np.full(residuals.shape[1], np.nan)
    for j in range(residuals.shape[1]):
        column = residuals[:, j]
        column = column[np.isfinite(column)]
        if len(column) >= 8:
            taus[j] = integrated_autocorrelation(column)
    finite = taus[np.isfinite(taus)]
    return max(floor, float(finite.max())) if len(finite) else floor, taus


def residual_correlation(model, base, beta, points, use, offsets=None, floor: float = 1.0) -> tuple[float, np.ndarray]:
    """``correlation_factor`` of the base estimate beta's residuals on consecutive fit
    points (``signals.FitPoints``); ``use`` (K, n): the rows that were fitted (others left out)."""
    from irb140_dynamics.core.regressor import regressor_batch

    residuals = np.empty(points.tau.shape)
    for start in range(0, len(points), 2048):
        part = slice(start, start + 2048)
        Y = base.columns(regressor_batch(model, points.q[part], points.qd[part], points.qdd[part]))
        residuals[part] = Y @ beta - points.tau[part]
    if offsets is not None:
        residuals += offsets
    return correlation_factor(np.where(use, residuals, np.nan), floor)
