"""Least squares on accumulated normal equations: memory independent of the data's length.

Per joint j the fit points' regressor rows y (13 n,) and torques tau are summed into

    A_j = sum y y^T,   b_j = sum y tau,   c_j = sum tau^2,   rows_j

which is all that least squares needs, and gives any parameter vector's residual sum of
squares on those rows exactly: RSS_j(pi) = pi^T A_j pi - 2 b_j^T pi + c_j.

The base parameters are estimated by weighted least squares, each joint's rows weighted by
1 / sigma_j^2, sigma_j its residual standard deviation (from ordinary least squares, then
once more from the weighted fit). Their covariance is s^2 kappa (sum_j A_j,b / sigma_j^2)^-1:
s^2 the weighted residual variance per degree of freedom (~1), kappa the correction for the
noise correlation between fit points that the smoothing leaves (``FilterDesign``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from irb140_dynamics.identification.base import BaseParameters


class NormalEquations:
    """Per-joint sums of the regressor's rows (see the module's docstring), and peak torques."""

    def __init__(self, n: int, parameters: int):
        self.A = np.zeros((n, parameters, parameters))
        self.b = np.zeros((n, parameters))
        self.c = np.zeros(n)
        self.rows = np.zeros(n, dtype=np.int64)
        self.peak = np.zeros(n)  # largest |tau| seen, N m

    def add(self, Y: np.ndarray, tau: np.ndarray, use: np.ndarray) -> None:
        """Add fit points: Y (K, n, P), tau (K, n), use (K, n) which rows count.

        Per joint only the regressor's columns that are not all zero enter the products
        (joint j moves no link before it: for the IRB-140 about a third of the work), the
        rows not used multiplied by zero rather than gathered: from regressor_batch's layout
        Y[:, j, :].T is contiguous, and A_j's update one symmetric product."""
        for j in range(self.A.shape[0]):
            w = use[:, j]
            rows = int(np.count_nonzero(w))
            if rows == 0:
                continue
            Yt = Y[:, j, :].T
            columns = np.flatnonzero((Yt != 0.0).any(axis=1))
            X = Yt[columns] * w
            self.A[j][np.ix_(columns, columns)] += X @ X.T
            self.b[j][columns] += X @ tau[:, j]
            tj = tau[w, j]
            self.c[j] += tj @ tj
            self.rows[j] += rows
            self.peak[j] = max(self.peak[j], float(np.abs(tj).max()))

    def rss(self, pi: np.ndarray) -> np.ndarray:
        """Residual sum of squares per joint of the full parameters pi (13 n,)."""
        pi = np.asarray(pi, dtype=float)
        rss = np.einsum("p,jpq,q->j", pi, self.A, pi) - 2.0 * self.b @ pi + self.c
        return np.maximum(rss, 0.0)

    def rms(self, pi: np.ndarray) -> np.ndarray:
        """RMS torque error per joint [N m] (nan for a joint without rows)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.sqrt(self.rss(pi) / self.rows)

    def base(self, base: BaseParameters) -> tuple[np.ndarray, np.ndarray]:
        """(A_j,b (n, r, r), b_j,b (n, r)): the sums of the base regressor's rows."""
        i = base.independent
        return self.A[:, i[:, None], i[None, :]], self.b[:, i]


@dataclass(frozen=True, eq=False)
class Estimate:
    """Weighted least-squares base parameters and their uncertainty."""

    beta: np.ndarray  # (r,)
    covariance: np.ndarray  # (r, r)
    sigma: np.ndarray  # (n,) residual standard deviation per joint, N m
    condition_number: float  # of the stacked base regressor (unweighted rows)
    rows: int

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.diag(self.covariance))

    def information(self) -> np.ndarray:
        """The covariance's inverse."""
        return np.linalg.inv(self.covariance)


def weighted_least_squares(data: NormalEquations, base: BaseParameters, correlation: float = 1.0) -> Estimate:
    """The base parameters from ``data`` (see the module's docstring)."""
    A, b = data.base(base)
    rows = data.rows.astype(float)
    r = base.count
    total = rows.sum()
    if total <= r:
        raise ValueError(f"{int(total)} torque rows for {r} base parameters: record more motion")
    unweighted = A.sum(axis=0)
    singular = np.linalg.svd(unweighted, compute_uv=False)
    condition = float(np.sqrt(singular[0] / singular[-1])) if singular[-1] > 0 else float("inf")
    if singular[-1] <= singular[0] * 1e-14:
        raise ValueError(
            "the recording does not excite every base parameter (singular regressor): "
            "run an excitation trajectory (`excitation`)"
        )
    weights = np.ones_like(rows)
    beta = None
    used = rows > 0
    # the RSS from the sums is a difference of terms ~ c_j: below ~1e-7 of the RMS torque a
    # sigma is their rounding (exact torques), and weights from it would be noise
    resolution = 1e-7 * np.sqrt(data.c / np.maximum(rows, 1.0))
    for _ in range(3):  # ordinary least squares, then weighted twice
        information = np.einsum("j,jpq->pq", weights, A)
        beta = np.linalg.solve(information, np.einsum("j,jp->p", weights, b))
        rss = _base_rss(A, b, data.c, beta)
        sigma = np.sqrt(rss / np.maximum(rows - r * rows / total, 1.0))
        floor = np.maximum(resolution, 1e-12 * max(float(sigma[used].max(initial=0.0)), 1e-300))
        weights = np.where(used, 1.0 / np.maximum(sigma, floor) ** 2, 0.0)
    information = np.einsum("j,jpq->pq", weights, A)
    beta = np.linalg.solve(information, np.einsum("j,jp->p", weights, b))
    s2 = float(weights @ _base_rss(A, b, data.c, beta)) / (total - r)
    covariance = np.linalg.inv(information) * s2 * correlation
    return Estimate(beta, (covariance + covariance.T) / 2.0, sigma, condition, int(total))


def _base_rss(A, b, c, beta):
    return np.maximum(np.einsum("p,jpq,q->j", beta, A, beta) - 2.0 * b @ beta + c, 0.0)
