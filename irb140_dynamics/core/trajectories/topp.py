"""Time-optimal path parameterization by reachability analysis (TOPP-RA, Pham and Pham 2018)
on a grid s_0 < ... < s_N over the path parameter.

The state at grid point i is x_i = sd_i^2, the control u_i = sdd, constant over
[s_i, s_i+1], so x_i+1 = x_i + 2 Delta_i u_i. At each grid point the limits are rows

    alpha_r u + beta_r x <= gamma_r,      0 <= x <= X_i

(see ``retime`` for how torque, velocity and acceleration limits become rows). Split by
the sign of alpha, they bound u from above (U_i(x) = min_r (gamma_r - beta_r x) / alpha_r)
and from below (L_i(x), the max). Backward, the controllable sets K_i = [0, k_i] (x from
which the end, at rest, can still be reached): k_N = 0, and k_i the largest x <= X_i with
L_i(x) <= U_i(x) and x + 2 Delta_i L_i(x) <= k_i+1, each a linear inequality per row, so
closed form. Forward, from rest, the largest u keeping x_i+1 in K_i+1. The result is the
time-optimal profile on the grid (the greedy forward pass through controllable sets is
optimal, Pham and Pham 2018, theorem 2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BIG = 1e300


def max_velocity_curve(alpha, beta, gamma, X) -> np.ndarray:
    """The largest x <= X_i at each grid point with some u satisfying every row: rows
    (N+1, R) -> (N+1,). An upper row p and a lower row q (on u) agree iff
    A_p - B_p x >= A_q - B_q x, linear in x; rows with alpha 0 bound x alone."""
    A, B, up, low = _split(alpha, beta, gamma)
    pu, pl = _first(up), _first(low)  # each point's upper (lower) rows first
    take = np.take_along_axis
    Au, Bu, mu = take(A, pu, 1), take(B, pu, 1), take(up, pu, 1)
    Al, Bl, ml = take(A, pl, 1), take(B, pl, 1), take(low, pl, 1)
    dB = np.where(mu[:, :, None] & ml[:, None, :], Bu[:, :, None] - Bl[:, None, :], 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        pair = np.where(dB > 0, (Au[:, :, None] - Al[:, None, :]) / dB, np.inf).min(axis=(1, 2))
        flat = (alpha == 0) & (beta > 0)
        alone = np.where(flat, gamma / np.where(flat, beta, 1.0), np.inf).min(axis=1)
    return np.maximum(np.minimum(np.minimum(X, pair), alone), 0.0)


@dataclass
class Profile:
    """A solved grid: per point the cap on x, the backward and forward rows (lists, for
    the loops), the controllable bounds k, and x, u; kept to solve again after a change."""

    X: list
    Q: list
    invP: list
    Au: list
    Bu: list
    k: list
    x: list
    u: list


def topp(alpha, beta, gamma, X, delta, stops, warm: Profile | None = None, changed=None):
    """x (N+1,), u (N,) of the time-optimal profile from rest to rest and its Profile;
    ``stops`` (N+1,) forces x = 0 where True; delta (N,) the grid steps. With ``warm`` (the
    profile before) and ``changed`` (the points whose rows changed; the others' rows as
    before), only the part of the grid the change reaches is solved again."""
    N = len(delta)
    points = np.arange(N + 1) if warm is None else np.unique(np.asarray(changed, dtype=int))
    rows = _prepare(alpha[points], beta[points], gamma[points], X[points], np.r_[delta, 1.0][points], stops[points])
    if warm is None:
        p = Profile(*rows, k=[0.0] * (N + 1), x=[0.0] * (N + 1), u=[0.0] * N)
        lo, hi = 0, N
    else:
        p = Profile(*(list(v) for v in (warm.X, warm.Q, warm.invP, warm.Au, warm.Bu, warm.k, warm.x, warm.u)))
        for i, *values in zip(points.tolist(), *rows):
            for field, value in zip((p.X, p.Q, p.invP, p.Au, p.Bu), values):
                field[i] = value
        lo, hi = int(points[0]), int(points[-1])
    # backward: x (1 - 2 delta B_q) <= k - 2 delta A_q for every lower row q with 1 - 2 delta B_q > 0
    k, Q, invP, Xl = p.k, p.Q, p.invP, p.X
    first_k = hi + 1
    for i in range(min(hi, N - 1), -1, -1):
        nxt = k[i + 1]
        value = max(min(Xl[i], min([(nxt - q) * w for q, w in zip(Q[i], invP[i])])), 0.0)
        if value == k[i] and i < lo and warm is not None:
            break
        k[i], first_k = value, i
    # forward: the largest u, x_i+1 within K_i+1
    x, u, Au, Bu, dl = p.x, p.u, p.Au, p.Bu, delta.tolist()
    last = hi if warm is None else max(hi, lo)
    for i in range(max(min(lo, first_k) - 1, 0), N):
        xi, two = x[i], 2.0 * dl[i]
        umax = min([a - b * xi for a, b in zip(Au[i], Bu[i])])
        nxt = min(max(xi + two * min(umax, (k[i + 1] - xi) / two), 0.0), k[i + 1])
        same = nxt == x[i + 1]
        x[i + 1], u[i] = nxt, (nxt - xi) / two
        if same and i >= last and warm is not None:
            break
    return np.array(x), np.array(u), p


def _prepare(alpha, beta, gamma, X, delta, stops):
    """Per point: the cap on x (the max velocity curve and the rows that cannot decelerate
    enough to reach x >= 0), the backward rows (Q, 1/P) and the upper rows (A, B) as lists;
    ``delta`` each point's step ahead (any number for the last point)."""
    A, B, up, low = _split(alpha, beta, gamma)
    X = max_velocity_curve(alpha, beta, gamma, X)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        slope = B - 1.0 / (2.0 * delta[:, None])
        reach = np.where(up & (slope > 0), A / slope, np.inf).min(axis=1)
    X = np.maximum(np.minimum(X, reach), 0.0)
    X[stops] = 0.0
    P = 1.0 - 2.0 * delta[:, None] * B
    use = low & (P > 0)
    Q = np.where(use, 2.0 * delta[:, None] * A, -BIG)  # unused rows: (k + BIG) * 1
    invP = 1.0 / np.where(use, P, 1.0)
    Au, Bu = np.where(up, A, BIG), np.where(up, B, 0.0)  # unused rows: BIG
    back, ahead = _first(use), _first(up)
    take = np.take_along_axis
    return (
        X.tolist(),
        *(take(v, back, 1).tolist() for v in (Q, invP)),
        *(take(v, ahead, 1).tolist() for v in (Au, Bu)),
    )


def _first(used) -> np.ndarray:
    """Column indices putting each row's used entries first, cut as far as no row needs more."""
    width = max(int(used.sum(axis=1).max()), 1)
    return np.argsort(~used, axis=1, kind="stable")[:, :width]


def _split(alpha, beta, gamma):
    """A = gamma / alpha, B = beta / alpha (u <= A - B x on rows with alpha > 0, u >= on rows
    with alpha < 0) and the two masks."""
    up, low = alpha > 0, alpha < 0
    safe = np.where(alpha != 0, alpha, 1.0)
    A = np.where(up | low, gamma / safe, 0.0)
    B = np.where(up | low, beta / safe, 0.0)
    return A, B, up, low
