"""Rigorous upper bounds of harmonic sums (see ``harmonic``) over boxes of angles.

Units: rad. A box has centre m and half-widths r per joint; with t = theta - m each factor
is re-expanded about m:

    cos(theta) = cos m (1 - v) - sin m s,   sin(theta) = sin m (1 - v) + cos m s,
    s = sin t in [-sin r, sin r],           v = 1 - cos t in [0, 1 - cos r],

and the sum becomes one over products of 1, v and s (``expand``). Counting v as degree 2,
the terms of degree >= 3 are bounded by their size (a product of v alone has the sign of
its coefficient); the rest is a quadratic model g . s + s^T Q s / 2 (``model``): b v <= b
s^2 / 2 for b < 0 (v >= s^2 / 2), b v <= b s^2 / (1 + cos r) for b >= 0. Its maximum
over the box is bounded by ``quadratic_max``, exact where the model is concave with its
top inside the box, so a box's bound is off by O(r^3) near a maximum.

Floating-point rounding: each term of an expansion passes d stages of two operations on
factors of size <= 1, and a row of the expansion adds up to at most 2.25 in size, so the
bounds computed are within ``rounding(d)`` times the sum of the coefficients' sizes of
the exact ones; ``certify`` adds that.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np

U = np.finfo(float).eps / 2  # unit roundoff
_WIDE = 3.0  # rad: a half-width past which 1 - cos t is bounded by its size alone
_CELLS = 1 << 16  # coefficients expanded at once (512 kB)


def rounding(d: int) -> float:
    """The rounding error of a bound over d joints, relative to the coefficients' sizes."""
    return (4 * d + 16) * U * 2.25**d


def expand(coefficients, centre):
    """The sums (B, ..., 3^d) re-expanded about the centres (B, d), each box's sums about its
    own centre: factors 1, v, s per joint."""
    coefficients = np.asarray(coefficients, dtype=float)
    B, d = centre.shape
    shape = coefficients.shape
    size = 3**d
    c = coefficients.size // max(B * size, 1)  # sums per box: one rotation each joint serves them all
    c_, s_ = np.cos(centre), np.sin(centre)
    M = np.zeros((B, d, 3, 3))  # row: 1, cos theta, sin theta; column: 1, v, s
    M[:, :, 0, 0] = 1.0
    M[:, :, 1, 0], M[:, :, 1, 1], M[:, :, 1, 2] = c_, -c_, -s_
    M[:, :, 2, 0], M[:, :, 2, 1], M[:, :, 2, 2] = s_, -s_, c_
    flat = coefficients.reshape(B, c * size)
    result = np.empty((B, c * size))
    step = max(1, _CELLS // (c * size))
    for first in range(0, B, step):  # a few boxes at a time: each pass's output stays in the caches
        rows = slice(first, first + step)
        D = flat[rows]
        b = D.shape[0]
        for k in range(d - 1, -1, -1):  # the last joint first; each pass turns the axes once (out=: a view)
            turned = result[rows] if k == 0 else np.empty((b, c * size))  # (the last pass: into the result)
            np.matmul(
                D.reshape(b, c, size // 3, 3), M[rows, k, None], out=turned.reshape(b, c, 3, size // 3).swapaxes(2, 3)
            )
            D = turned
        if d == 0:
            result[rows] = D
    return result.reshape(shape)


def sizes(radius):
    """The largest size of each product of factors 1, v, s over the boxes (B, 3^d)."""
    B, d = radius.shape
    factor = np.stack([np.ones((B, d)), 1 - np.cos(np.minimum(radius, math.pi)), sizes_of_s(radius)], axis=2)
    W = np.ones((B, 1))
    for k in range(d):
        W = (W[:, :, None] * factor[:, k, None, :]).reshape(B, -1)
    return W


def sizes_of_s(radius):
    """max |sin t| for |t| <= radius."""
    return np.where(radius < math.pi / 2, np.sin(np.minimum(radius, math.pi / 2)), 1.0)


def model(D, W, radius):
    """A re-expanded sum, its constant term left out, as g . s + s^T Q s / 2 plus at most
    ``high`` over the boxes; and the size of each term (B, 3^d), for choosing a split."""
    B, d = radius.shape
    where = layout(d)
    terms = np.where(where.signed, np.maximum(D, 0.0), np.abs(D)) * W
    g, b = D[:, where.single_s], D[:, where.single_v]
    wide = radius > _WIDE
    curvature = np.where(b < 0, b, np.where(wide, 0.0, 2 * b / (1 + np.cos(np.minimum(radius, _WIDE)))))
    high = terms[:, where.high].sum(axis=1) + np.where(wide & (b >= 0), terms[:, where.single_v], 0.0).sum(axis=1)
    Q = np.zeros((B, d, d))
    k, l = where.upper
    Q[:, k, l] = Q[:, l, k] = D[:, where.pair]
    Q[:, where.diagonal, where.diagonal] = curvature
    return g, Q, high, terms


def quadratic_max(g, Q, sigma, enough=None):
    """An upper bound of g . s + s^T Q s / 2 over |s_k| <= sigma_k (B boxes): the smaller
    of (1) each term maximised on its own, the products s_k s_l by size, and (2) the
    Lagrangian dual sum mu_k sigma_k^2 + g^T S^-1 g / 2, S = 2 diag(mu) - Q positive
    definite, valid for any mu >= 0 and exact when Q is concave with its top in the box:
    mu by two sweeps of exact coordinate descent from a diagonally dominant start, the
    value from an eigendecomposition, enlarged by its possible rounding error. The dual
    only where (1) is above ``enough`` (B,), if given."""
    B, d = g.shape
    if d == 0:
        return np.zeros(B)
    absQ = np.abs(Q)
    diagonal = np.diagonal(Q, axis1=1, axis2=2)
    off = absQ.sum(axis=2) - np.abs(diagonal)
    with np.errstate(divide="ignore", invalid="ignore"):
        vertex = (diagonal < 0) & (np.abs(g) <= -diagonal * sigma)
        alone = np.where(
            vertex, g * g / np.where(diagonal < 0, -2 * diagonal, 1.0), np.abs(g) * sigma + 0.5 * diagonal * sigma**2
        )
    cross = np.einsum("bkl,bk,bl->b", absQ, sigma, sigma) - (np.abs(diagonal) * sigma**2).sum(axis=1)
    bound = alone.sum(axis=1) + 0.5 * cross
    rows = np.arange(B) if enough is None else np.flatnonzero(bound > enough)
    if rows.size:
        dual = _dual(g[rows], Q[rows], np.maximum(sigma[rows], 1e-9), diagonal[rows], off[rows])  # wider: still a bound
        bound[rows] = np.minimum(bound[rows], dual)
    return bound


def _dual(g, Q, sigma, diagonal, off):
    B, d = g.shape
    size = np.abs(Q).max(axis=(1, 2)) + (np.abs(g) / sigma).max(axis=1) + 1e-300
    mu = 0.5 * np.maximum(0.0, diagonal + off) + np.abs(g) / (2 * sigma) + 1e-9 * size[:, None]
    rows = layout(d).diagonal
    S = -Q
    S[:, rows, rows] += 2 * mu
    inverse = np.linalg.inv(S)
    x = np.einsum("bkl,bl->bk", inverse, g)
    # the sweeps on (d, ..., B) arrays: each k's numbers in a row
    inverse, x, mu, sigma_k = inverse.transpose(1, 2, 0).copy(), x.T.copy(), mu.T.copy(), sigma.T
    for _ in range(2):
        for k in range(d):  # the best mu_k for the others (Sherman-Morrison), S kept definite
            h = inverse[k, k]
            step = np.maximum((np.maximum(np.abs(x[k]) / sigma_k[k], 0.01) - 1) / (2 * h), -mu[k])
            scale = 2 * step / (1 + 2 * step * h)
            column = inverse[:, k].copy()
            x -= (scale * x[k]) * column
            inverse -= (scale * column)[:, None] * column
            mu[k] += step
    mu = mu.T
    S = -Q
    S[:, rows, rows] += 2 * np.maximum(mu, 0.0)
    lam, V = np.linalg.eigh(S)
    # the computed eigenpairs are exact for S + E, |E| <= 16 d U |S|: S >= (1 - eta)(S + E)
    eta = 16 * d * U * np.sqrt((S**2).sum(axis=(1, 2))) / np.where(lam[:, 0] > 0, lam[:, 0], 1.0)
    trusted = (lam[:, 0] > 0) & (eta < 0.5)
    with np.errstate(divide="ignore", invalid="ignore"):
        projected = np.einsum("bkj,bk->bj", V, g)
        value = (np.maximum(mu, 0.0) * sigma**2).sum(axis=1) + 0.5 * (projected**2 / lam).sum(axis=1) / (1 - eta)
    return np.where(trusted, value * (1 + 16 * d * U), np.inf)


@dataclass(frozen=True)
class Layout:
    """Where the terms of a sum over d joints are (the first joint slowest)."""

    involves: np.ndarray  # (3^d, d): 1 where the term has a factor of joint k
    signed: np.ndarray  # terms without an s factor: their sign is their coefficient's
    high: np.ndarray  # terms of degree >= 3
    single_s: np.ndarray  # the term s_k alone, per k
    single_v: np.ndarray  # v_k alone
    pair: np.ndarray  # s_k s_l, k < l
    upper: tuple[np.ndarray, np.ndarray]  # (k, l) of those pairs
    higher: np.ndarray  # terms other than the constant and the s_k alone
    diagonal: np.ndarray  # 0 .. d - 1


@cache
def layout(d: int) -> Layout:
    digits = np.indices((3,) * d, dtype=int).reshape(d, -1).T if d else np.zeros((1, 0), int)
    degree = np.where(digits == 1, 2, np.where(digits == 2, 1, 0)).sum(axis=1)
    place = 3 ** np.arange(d - 1, -1, -1)
    k, l = np.triu_indices(d, 1)
    return Layout(
        involves=(digits != 0).astype(float),
        signed=~(digits == 2).any(axis=1),
        high=degree >= 3,
        single_s=2 * place,
        single_v=place,
        pair=2 * place[k] + 2 * place[l],
        upper=(k, l),
        higher=np.isin(np.arange(3**d), 2 * place, invert=True) & (np.arange(3**d) != 0),
        diagonal=np.arange(d),
    )


def squared_model(N, W, sigma, radius):
    """For a vector of sums re-expanded about the centres, N (B, c, 3^d): |v| at the
    centres, and |v|^2 <= squared + 2 g . s + s^T Q s over the boxes; each term's weight
    (B, 3^d), for choosing a split.

    |v|^2 = |v(c)|^2 + 2 v(c) . delta + |delta|^2, delta = v - v(c) = A s + rest: the first
    two terms as a quadratic model, |delta|^2 <= |A s|^2 + 2 |A s| |rest| + |rest|^2 by the
    sizes of the terms."""
    return _squared_model(N, W, sigma, radius)[:5]


def _squared_model(N, W, sigma, radius):
    """``squared_model``, and the sizes of each sum's terms of degree >= 2 (B, c)."""
    where = layout(radius.shape[1])
    middle = N[:, :, 0]
    along = np.einsum("bc,bca->ba", middle, N)
    along[:, 0] = 0.0
    g_v, Q_v, high_v, along_terms = model(along, W, radius)
    A = N[:, :, where.single_s]  # (B, c, d)
    rest = np.abs(N) * W[:, None]
    terms = along_terms + rest.sum(axis=1)
    rest[:, :, 0] = 0.0
    rest[:, :, where.single_s] = 0.0
    higher = rest.sum(axis=2)
    rest = np.sqrt((higher**2).sum(axis=1))
    linear = (np.sqrt((A**2).sum(axis=1)) * sigma).sum(axis=1)
    size = np.sqrt((middle**2).sum(axis=1))
    squared = size**2 + 2 * high_v + 2 * linear * rest + rest**2
    return size, squared, g_v, Q_v + np.einsum("bck,bcl->bkl", A, A), terms, higher


def turned_squared_max(N, W, sigma, radius, turn, enough=None):
    """For vectors a + X cos(phi) + Y sin(phi), phi over a whole turn, given as the sums of
    a, X, Y (3 each) re-expanded about the centres, N (B, 9, 3^d), with ``turn`` (B,) >=
    |X cos(phi) + Y sin(phi)| everywhere: an upper bound of the largest |.|^2 over the boxes
    and every phi, its limit at the centres (a bound there), each term's weight.

    With B = [X Y] and u a unit vector, |a + B u|^2 <= |a|^2 + 2 |w| + turn^2, w = B^T a
    (exact where the best u for w is B's first singular vector: a CoM offset turned fully
    outward, or along the flange axis). With b = |w(c)| > 0, e = w(c) / b and delta = w -
    w(c), |w| <= b/2 + |w|^2 / (2 b) = b + e . delta + |delta|^2 / (2 b): e . delta to second
    order exactly (the products' linear and bilinear parts; the rest by sizes), |delta|^2 as
    |J s|^2 plus terms of degree >= 3 (J: w's linear part), one quadratic model with |a|^2's
    (``squared_model``), off by O(r^3) like it. Also, for b near 0: |a|^2's bound plus 2 (b +
    sum |J_k| sigma_k + the size of w's terms of degree >= 2); the smaller of the two."""
    B, _, size_d = N.shape
    where = layout(radius.shape[1])
    a, X = N[:, :3], N[:, 3:].reshape(B, 2, 3, size_d)
    size, squared, g, Q, terms, Ha = _squared_model(a, W, sigma, radius)
    a0, X0 = a[:, :, 0], X[:, :, :, 0]
    Aa, AX = a[:, :, where.single_s], X[:, :, :, where.single_s]
    w0 = np.einsum("bc,bpc->bp", a0, X0)
    J = np.einsum("bck,bpc->bpk", Aa, X0) + np.einsum("bc,bpck->bpk", a0, AX)
    higher = where.higher
    sized = np.abs(X) * W[:, None, None]
    HX = (sized * higher).sum(axis=3)
    La, LX = np.einsum("bck,bk->bc", np.abs(Aa), sigma), np.einsum("bpck,bk->bpc", np.abs(AX), sigma)
    first = np.einsum("bpa,ba->bp", np.abs(np.einsum("bc,bpca->bpa", a0, X * higher)), W)
    first = first + np.einsum("bpa,ba->bp", np.abs(np.einsum("bpc,bca->bpa", X0, a * higher)), W)
    products = np.einsum("bc,bpc->bp", La + Ha, LX + HX)  # |delta a . delta X_p|
    rest = np.sqrt(((first + products) ** 2).sum(axis=1))  # |w - w(c) - J s|
    b = np.sqrt((w0**2).sum(axis=1))
    linear = (np.sqrt((J**2).sum(axis=1)) * sigma).sum(axis=1)
    bound = squared + turn**2 + 2 * (b + linear + rest) + quadratic_max(2 * g, 2 * Q, sigma)
    rows = np.flatnonzero((b > 0) & (True if enough is None else ~(bound <= enough)))
    if rows.size:
        e, k = w0[rows] / b[rows, None], 1.0 / b[rows]
        D = np.einsum("bp,bc,bpca->ba", e, a0[rows], X[rows]) + np.einsum("bp,bpc,bca->ba", e, X0[rows], a[rows])
        g1, Q1, high1, _ = model(D, W[rows], radius[rows])  # e . (a(c) . X + X(c) . a): all but delta a . delta X
        M = np.einsum("bp,bck,bpcl->bkl", e, Aa[rows], AX[rows])  # e . (delta a . delta X): its bilinear part...
        bilinear_rest = np.einsum("bp,bc,bpc->b", np.abs(e), La[rows], HX[rows])  # ...and the rest
        bilinear_rest = bilinear_rest + np.einsum("bp,bc,bpc->b", np.abs(e), Ha[rows], LX[rows] + HX[rows])
        JJ = np.einsum("bpk,bpl->bkl", J[rows], J[rows]) * k[:, None, None]
        g_all = 2 * g[rows] + 2 * g1
        Q_all = 2 * Q[rows] + 2 * Q1 + 2 * (M + M.transpose(0, 2, 1)) + 2 * JJ
        constant = squared[rows] + turn[rows] ** 2 + 2 * b[rows] + 2 * (high1 + bilinear_rest)
        constant = constant + (2 * linear[rows] * rest[rows] + rest[rows] ** 2) * k
        enough_rows = None if enough is None else enough[rows] - constant
        modelled = constant + quadratic_max(g_all, Q_all, sigma[rows], enough_rows)
        bound[rows] = np.fmin(bound[rows], modelled)  # (nan: the other)
    bound = bound * (1 + 1e-12) + 1e-12 * (squared + turn**2 + 2 * b)  # (the rounding of the products)
    weight = terms + sized.sum(axis=(1, 2)) * size[:, None]
    return np.sqrt(size**2 + 2 * b + turn**2), bound, weight
