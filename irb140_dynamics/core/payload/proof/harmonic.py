"""Static torques as finite harmonic sums with rigorous coefficients: what ``certify`` bounds.

Units: rad, N m. With qd = qdd = 0 a torque is, in each joint angle theta_k = q_k +
offset_k, A + B cos(theta_k) + C sin(theta_k) (see ``workspace``), so over all the angles

    tau_j(theta) = sum over alpha in {0, 1, 2}^n of c_alpha prod_k phi[alpha_k](theta_k),
    phi = (1, cos, sin).

The 3^n coefficients follow from the torques at theta_k in {0, pi/2, pi}, where (cos, sin)
= (1, 0), (0, 1), (-1, 0) exactly: A = (f(0) + f(pi)) / 2, B = (f(0) - f(pi)) / 2,
C = f(pi/2) - A, one angle after the other. ``algorithms.rnea`` evaluates those torques on
Interval numbers, so each coefficient comes as an enclosure of its exact value; the sum is
exact: no cancellation is lost (cos^2 + sin^2 = 1 has been used up by the fit), which is
what makes the bounds tight.

Besides tau_j, ``certify`` uses omega_j: joint j's torque per unit of gravity along each
axis of frame j (the frame joint j turns in), a sum over the joints after j. Static torques
are linear in gravity, so tau_j = g_j . omega_j with g_j the gravity in frame j, and
|tau_j| <= |g| |omega_j|; turning joint j turns omega_j about its axis, so |omega_j| does
not depend on theta_j, which is set to 0 (the subchain from link j, by rnea too).

Cost: 3^n torques for tau and about 3^n / 2 for the omegas, each one rnea pass on Interval
arrays (3^6 = 729 states for six joints), on a grid with an axis per joint: what depends on
the first joints only is computed once per their values. Beyond MAX_JOINTS joints the sums grow too large
and ``certify`` falls back to plain interval bounds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.core.scalars.interval import Interval, bounds_of

MAX_JOINTS = 9  # 3^9 = 19683 coefficients per sum
NOISE = 1e-14  # a joint whose terms weigh less than this fraction of a sum is dropped from it
_COS, _SIN = np.array([1.0, 0.0, -1.0]), np.array([0.0, 1.0, 0.0])  # theta = 0, pi/2, pi


@dataclass(frozen=True, eq=False)
class HarmonicSum:
    """sum_alpha c_alpha prod_k phi[alpha_k](theta[dims[k]]) for c_alpha within ``coefficients``
    (an Interval of shape (..., 3^len(dims)); leading axes for several sums at once)."""

    dims: tuple[int, ...]
    coefficients: Interval

    def __add__(self, other: HarmonicSum) -> HarmonicSum:
        assert self.dims == other.dims
        return HarmonicSum(self.dims, self.coefficients + other.coefficients)

    def __sub__(self, other: HarmonicSum) -> HarmonicSum:
        return self + other * -1.0

    def __mul__(self, k: float) -> HarmonicSum:
        return HarmonicSum(self.dims, self.coefficients * float(k))

    def __getitem__(self, index) -> HarmonicSum:
        c = self.coefficients
        return HarmonicSum(self.dims, Interval(c.lo[index], c.hi[index]))

    def reduced(self, merge: bool = False) -> Reduced:
        """Midpoint coefficients and an error bound, without the joints it hardly depends on
        (whose terms then count in the error: |phi| <= 1); with ``merge``, joints it depends
        on only through theta_a +- theta_b become one (``merge_parallel``; several sums:
        only where all of them do)."""
        c, d = self.coefficients, len(self.dims)
        lead = c.lo.shape[:-1]
        mid = c.mid.reshape(lead + (3,) * d)
        error = c.rad.reshape(lead + (-1,)).sum(axis=-1)
        weight = np.abs(mid).reshape((-1,) + (3,) * d).sum(axis=0)
        total = weight.sum()
        dims = list(self.dims)
        for axis in reversed(range(d)):
            if np.take(weight, [1, 2], axis=axis).sum() <= NOISE * total:
                dropped = np.take(mid, [1, 2], axis=len(lead) + axis)
                error = error + np.abs(dropped).reshape(lead + (-1,)).sum(axis=-1)
                mid, weight = np.take(mid, 0, axis=len(lead) + axis), np.take(weight, 0, axis=axis)
                del dims[axis]
        merges: list[tuple[int, int, float]] = []
        if merge:
            leading = tuple(range(len(lead)))
            trailing = tuple(range(-len(lead), 0))
            merged, residual = merge_parallel(np.moveaxis(mid, leading, trailing), dims, merges, NOISE * total)
            mid, error = np.moveaxis(merged, trailing, leading), error + residual
        return Reduced(tuple(dims), mid.reshape(lead + (-1,)), np.asarray(error, dtype=float), tuple(merges))

    def over_direction(self) -> HarmonicSum:
        """Sums whose last joint phi turns a payload's CoM about the flange axis (a whole
        turn): (A, X, Y) (a leading axis) over the other joints, each sum being A + X
        cos(phi) + Y sin(phi) exactly (only the CoM's offset turns with phi, its terms are
        of degree one in phi). A single sum's maximum over the directions is A + |(X, Y)|;
        A alone is the sum of the CoM on the axis."""
        c = self.coefficients
        lead = c.lo.shape[:-1]
        lo, hi = (np.moveaxis(x.reshape(lead + (-1, 3)), -1, 0) for x in (c.lo, c.hi))
        return HarmonicSum(self.dims[:-1], Interval(lo, hi))

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        """The midpoint sum at angles theta (N, n): (N, ...); for tests."""
        return np.einsum("pa,...a->p...", basis(np.atleast_2d(theta)[:, list(self.dims)]), self.coefficients.mid)


def basis(theta) -> np.ndarray:
    """prod_k phi[alpha_k](theta_k) for every alpha (the first joint slowest), at angles
    theta (N, d): (N, 3^d), the terms a sum's coefficients multiply."""
    terms = np.ones((len(theta), 1))
    for k in range(theta.shape[1]):
        phi = np.stack([np.ones(len(theta)), np.cos(theta[:, k]), np.sin(theta[:, k])], axis=1)
        terms = (terms[:, :, None] * phi[:, None, :]).reshape(len(theta), -1)
    return terms


@dataclass(frozen=True, eq=False)
class Reduced:
    """A harmonic sum with point coefficients (..., 3^len(dims)) and a bound on its error;
    ``merges`` (a, b, sign) in order: theta_b folded into theta_a as theta_a + sign theta_b."""

    dims: tuple[int, ...]
    coefficients: np.ndarray
    error: np.ndarray
    merges: tuple[tuple[int, int, float], ...] = ()

    def box(self, lower, upper) -> tuple[np.ndarray, np.ndarray]:
        """The box of angles this sum is over, from the joints' (n,): a merged joint a
        ranges over theta_a + sign theta_b, theta_b is 0."""
        lo, hi = np.array(lower, dtype=float), np.array(upper, dtype=float)
        for a, b, sign in self.merges:
            lo[a], hi[a] = (lo[a] + lo[b], hi[a] + hi[b]) if sign > 0 else (lo[a] - hi[b], hi[a] - lo[b])
            lo[b] = hi[b] = 0.0
        return lo, hi

    def fold(self, theta) -> np.ndarray:
        """Joint angles (K, n) as a point of ``box``: the inverse of ``angles``."""
        theta = np.array(theta, dtype=float, ndmin=2)
        for a, b, sign in self.merges:
            theta[:, a] += sign * theta[:, b]
            theta[:, b] = 0.0
        return theta

    def angles(self, theta, lower, upper) -> np.ndarray:
        """Joint angles (K, n) within [lower, upper] with the same sum as theta (K, n) from
        ``box``: each merged sum split back, theta_b near the middle of its range."""
        theta = np.array(theta, dtype=float, ndmin=2)
        lo, hi = np.array(lower, dtype=float), np.array(upper, dtype=float)
        before = []
        for a, b, sign in self.merges:
            before.append((lo[a], hi[a]))
            lo[a], hi[a] = (lo[a] + lower[b], hi[a] + upper[b]) if sign > 0 else (lo[a] - upper[b], hi[a] - lower[b])
        for (a, b, sign), (lo_a, hi_a) in zip(reversed(self.merges), reversed(before)):
            total, middle = theta[:, a].copy(), 0.5 * (lower[b] + upper[b])
            theta[:, a] = np.clip(total - sign * middle, lo_a, hi_a)
            theta[:, b] = np.clip(sign * (total - theta[:, a]), lower[b], upper[b])
        return theta


@dataclass(frozen=True, eq=False)
class StaticForms:
    """A model's static torques tau_j (one sum per joint, over all joints) and omega_j
    (three sums per joint, over the joints after it), and |g| rounded up."""

    torque: HarmonicSum
    omega: tuple[HarmonicSum, ...]
    gravity_norm: float
    sliding: tuple[tuple[float, float] | None, ...] = ()  # per joint: a prismatic one's (c, r), see ``slide``

    @classmethod
    def of(cls, model, most: int = MAX_JOINTS) -> StaticForms | None:
        """The forms of ``model`` (None beyond ``most`` joints)."""
        if model.n > most:
            return None
        kernels = kernels_of(model)
        sliding = tuple(slide(j.position_limits) if j.prismatic else None for j in model.independent_joints)
        return _forms(kernels.links, tuple(kernels.gravity), sliding)

    def affine(self, other: StaticForms, k: float) -> StaticForms:
        """self + k (other - self): the forms of a payload at k kg from those at 0 and 1 kg."""
        torque = self.torque + (other.torque - self.torque) * k
        omega = tuple(a + (b - a) * k for a, b in zip(self.omega, other.omega))
        return StaticForms(torque, omega, self.gravity_norm, self.sliding)

    def angles_of(self, q) -> np.ndarray:
        """A prismatic joint's displacements q [m] (..., n) as the angles of ``slide`` (rad),
        the revolute joints' values unchanged."""
        theta = np.array(q, dtype=float)
        for k, cr in enumerate(self.sliding):
            if cr is not None:
                c, r = cr
                theta[..., k] = np.arcsin(np.clip((theta[..., k] - c) / r, -1.0, 1.0)) if r > 0 else 0.0
        return theta

    def joints_of(self, theta) -> np.ndarray:
        """The inverse of ``angles_of``: d = c + r sin(theta) for the prismatic joints."""
        q = np.array(theta, dtype=float)
        for k, cr in enumerate(self.sliding):
            if cr is not None:
                q[..., k] = cr[0] + cr[1] * np.sin(q[..., k])
        return q


def slide(limits) -> tuple[float, float]:
    """A prismatic joint's range [lo, hi] as d = c + r sin(theta), theta in [-pi/2, pi/2]:
    (c, r) with [c - r, c + r] holding [lo, hi] (r rounded up). Static torques are affine
    in each displacement (a weight's lever arm is), so in theta they are A + C sin(theta):
    a harmonic sum like a revolute joint's, fitted from theta = 0, pi/2, pi as those are."""
    lo, hi = (float(x) for x in limits)
    c = 0.5 * (lo + hi)
    r = np.nextafter(np.nextafter(max(hi - c, c - lo, 0.0), np.inf), np.inf)
    return c, float(r)


def _forms(links, gravity, sliding) -> StaticForms:
    n = len(links)
    zeros = [0.0] * n
    values = algorithms.rnea(links, _circle_points(n, sliding=sliding), zeros, zeros, gravity)
    torque = _fit(_stack(values, (3,) * n), n)
    omega = []
    for j in range(n):
        rest = n - j - 1
        own = (sliding[j][0],) if sliding[j] is not None else (1.0, 0.0)  # (omega_j does not depend on it)
        cs = [own] + _circle_points(rest, lead=1, sliding=sliding[j + 1 :])
        unit_gravity = tuple(Interval(np.eye(3)[axis].reshape((3,) + (1,) * rest)) for axis in range(3))
        per_axis = algorithms.rnea(links[j:], cs, zeros[j:], zeros[j:], unit_gravity)[0]
        lo, hi = bounds_of(per_axis, (3,) * (rest + 1))
        omega.append(_fit(Interval(lo.reshape(3, -1), hi.reshape(3, -1)), rest, first=j + 1))
    norm = math.hypot(*gravity)
    return StaticForms(torque, tuple(omega), float(np.nextafter(norm * (1 + 4e-16), np.inf)), tuple(sliding))


def _circle_points(d: int, lead: int = 0, sliding=()) -> list:
    """(cos, sin) pairs for d joints at theta in {0, pi/2, pi}, joint k's along axis lead + k
    of a grid of lead + d axes (the first joint slowest; the arrays broadcast, so that what
    depends on the first joints only is computed once per their values, the same numbers);
    a prismatic joint's (c + r sin theta,)."""
    points = []
    for k in range(d):
        shape = (1,) * (lead + k) + (3,) + (1,) * (d - k - 1)
        cr = sliding[k] if k < len(sliding) else None
        c, s = Interval(_COS.reshape(shape)), Interval(_SIN.reshape(shape))
        points.append((c, s) if cr is None else (s * cr[1] + cr[0],))
    return points


def _stack(values, shape: tuple) -> Interval:
    """The sums' values (each over a grid ``shape``, or broadcasting to it) as (len, size) arrays."""
    bounds = [bounds_of(v, shape) for v in values]
    lo, hi = np.array([b[0] for b in bounds]), np.array([b[1] for b in bounds])
    return Interval(lo.reshape(len(values), -1), hi.reshape(len(values), -1))


def _fit(values: Interval, d: int, first: int = 0) -> HarmonicSum:
    """Coefficients from the values (..., 3^d) at theta in {0, pi/2, pi}^d."""
    lead = values.lo.shape[:-1]
    shape = lead + (3,) * d
    c = Interval(values.lo.reshape(shape), values.hi.reshape(shape))
    for axis in range(len(lead), len(shape)):
        at = [(slice(None),) * axis + (i,) for i in range(3)]  # (views, not copies)
        f0, f1, f2 = (Interval(c.lo[i], c.hi[i]) for i in at)
        A, B = (f0 + f2) * 0.5, (f0 - f2) * 0.5
        C = f1 - A
        c = Interval(np.empty(shape), np.empty(shape))
        for i, part in zip(at, (A, B, C)):
            c.lo[i], c.hi[i] = part.lo, part.hi
    flat = lead + (3**d,)
    return HarmonicSum(tuple(range(first, first + d)), Interval(c.lo.reshape(flat), c.hi.reshape(flat)))


def merge_parallel(T, dims: list, merges: list, noise: float):
    """T (3,)*d without pairs of neighbouring joints it depends on only through theta_a +-
    theta_b (parallel joints before the one whose torque it is: they only turn gravity),
    each pair folded into joint a (theta_b = 0; dims and merges updated); and the size of
    the terms that did not fit that form, for the error bound."""
    residual, p = 0.0, 0
    while p + 1 < len(dims):
        X = np.moveaxis(T, (p, p + 1), (0, 1))
        for sign in (1.0, -1.0):  # cos(a +- b) = ca cb -+ sa sb, sin(a +- b) = sa cb +- ca sb
            B, C = 0.5 * (X[1, 1] - sign * X[2, 2]), 0.5 * (X[2, 1] + sign * X[1, 2])
            fit = np.zeros_like(X)
            fit[0, 0], fit[1, 1], fit[2, 2], fit[2, 1], fit[1, 2] = X[0, 0], B, -sign * B, C, sign * C
            off = np.abs(X - fit).sum()
            if off <= noise:
                T = np.moveaxis(np.stack([X[0, 0], B, C]), 0, p)
                residual += off
                merges.append((dims[p], dims.pop(p + 1), sign))
                break
        else:
            p += 1
    return T, residual


def without_wrist(parts: HarmonicSum) -> HarmonicSum | None:
    """``over_direction``'s (A, X, Y) without their last joint b, where b turns the CoM's
    offset about the flange axis, X + iY = exp(+-i theta_b) (X0 + iY0): then A = A0 + P
    cos(theta_b) + Q sin(theta_b) and A + |(X, Y)| <= A0 + |(P, Q)| + |(X0, Y0)| (exact
    where b turns a whole turn). The sums (A0, P, Q, X0, Y0) over the joints before b, or
    None where b is not such (the terms that do not fit go to the constant coefficients'
    radius, as errors, when they are rounding noise)."""
    c = parts.coefficients
    mid, rad = c.mid.reshape(3, -1, 3), c.rad.reshape(3, -1, 3)
    A, X, Y = mid
    if not parts.dims:
        return None
    size = np.abs(mid[1:]).sum()
    for sign in (1.0, -1.0):  # X = cos(b) X0 - sign sin(b) Y0, Y = sign sin(b) X0 + cos(b) Y0
        X0, Y0 = 0.5 * (X[:, 1] + sign * Y[:, 2]), 0.5 * (Y[:, 1] - sign * X[:, 2])
        misfit = np.abs(X[:, 0]).sum() + np.abs(Y[:, 0]).sum() + np.abs(X[:, 1] - X0).sum() + np.abs(Y[:, 1] - Y0).sum()
        misfit += np.abs(Y[:, 2] - sign * X0).sum() + np.abs(X[:, 2] + sign * Y0).sum()
        if misfit <= NOISE * (size + np.abs(A).sum()):  # (X, Y) of a CoM on the axis: rounding noise
            kept = np.stack([A[:, 0], A[:, 1], A[:, 2], X0, Y0])
            error = np.zeros_like(kept)
            error[:3, 0] = rad[0].reshape(-1, 3).sum(axis=0) * (1 + 1e-12)
            error[3, 0] = (misfit + rad[1:].sum()) * (1 + 1e-12)
            return HarmonicSum(parts.dims[:-1], Interval(kept - error, kept + error))
    return None
