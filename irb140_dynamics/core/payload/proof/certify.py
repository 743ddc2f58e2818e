"""Certified maxima of static torques over a box of joint angles: branch and bound.

Units: rad, N m. The search in ``workspace`` finds poses and their torques: lower bounds
of the maxima. Here each maximum also gets an upper bound that is proven: the box is cut
into smaller boxes, each gets a rigorous upper bound of the objective over it, boxes whose
bound is below the best value known are dropped, the others are split (the joint that
weighs most in the bound, at its middle) until every bound is within ``tol`` of the best
value known, or the budget of box bounds is spent. The bound then is the largest bound of
a box kept; the gap, bound - best value, is what remains unproven. A box's centre that
beats the best value by more than tol shows a maximum the search missed: it is climbed
from (``polish``), and the real pose found serves as the best value from then on.

An objective is +-tau_j written as a harmonic sum (see ``harmonic``: joints it does not
depend on dropped, parallel joints before j merged into one angle). A box gets the smaller
of two bounds: the sum's own, a second-order expansion about the box's centre (see
``bounds``: off by O(r^3) near a maximum), and |tau_j| <= |g| |omega_j(theta after j)|
(Cauchy-Schwarz), which holds whatever the joints before j do: it closes the boxes along
the curves of poses that share a maximum (a wrist turning about its own axis, joints that
only turn gravity), where no expansion gets tight. With a payload's direction phi (see
``Objective``), omega_j = a + X cos(phi) + Y sin(phi) may be bounded without phi as an
angle (``Objective.turn``, ``bounds.turned_squared_max``): a straight arm's rolls leave
surfaces of near-maximum poses that the norm, over fewer joints, covers in far fewer boxes.
A box is split where the bound it gets weighs most. The norm is reached only where the
joints up to j can turn gravity in frame j to omega_j's direction; where they cannot at the
best pose known (a shoulder whose range ends before the arm is level, a torso that leans a
little), a box wider than TURNING in those joints is split by the value's terms: else the
norm's joints are cut ever finer while the box stays wide in the joints that bound the
maximum.

Rigour: the sums' coefficients are enclosures (Interval arithmetic); their widths and the
terms of the joints dropped are the sums' ``error``, and ``bounds.rounding`` covers the
floating-point rounding of a bound: both are added to each bound. The result is an upper
bound of the exact maxima of the model's static torques.

Cost: at most EVALUATIONS box bounds per call, each counted in units of a sum of TERMS
terms (a box over a sum of d joints costs O(d 3^d)), in batches of at most BATCH boxes:
the budget bounds the time whatever the model; for the IRB-140 and its rated payload the
proof closes long before it is spent. The analysis' stop (see ``stop``) is checked
before each batch: cancelled, the proof is abandoned; out of time, it ends as when the
budget is spent, its bounds proven but looser.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.payload.proof.bounds import (
    U,
    expand,
    layout,
    model,
    quadratic_max,
    rounding,
    sizes,
    sizes_of_s,
    squared_model,
    turned_squared_max,
)
from irb140_dynamics.core.payload.proof.harmonic import Reduced, basis
from irb140_dynamics.core.payload.stop import out_of_time

EVALUATIONS = 50_000  # box bounds per call, shared by the groups of objectives, counted in
TERMS = 200  # bounds of sums of this many terms (the IRB-140's): a box over more terms counts more
BATCH = 1024  # boxes bounded at once (the most promising first)
SLICE = 2048  # box bounds per turn of a group
TURNING = 1.0  # rad: a half-width of a joint turning gravity past which the norm does not choose the split...
REACHED = 0.99  # ...unless the best value known is at least this share of the norm at its pose


@dataclass(frozen=True, eq=False)
class Objective:
    """Maximise ``value`` + sum of |lever_p| over the box (lever: pairs of sums over the
    value's joints, merged alike, or none); the objective is at most gravity_norm |norm|
    too (norm: 3 sums, over the box's joints).

    A lever is a payload's CoM turned about the flange axis in the worst direction phi:
    the torque A + X cos(phi) + Y sin(phi) is at most A + |(X, Y)|, reached at some phi
    (see ``harmonic.HarmonicSum.over_direction``); one of a joint whose range is not a whole
    turn is not always reached (``reached``: the value at a box's centre counts -|lever|).
    With a ``turn``, the norm's sums are a, X, Y, and |omega| is their worst over a whole
    turn of the direction: at most sqrt(|a|^2 + 2 |(X . a, Y . a)| + turn^2)."""

    value: Reduced
    norm: Reduced
    gravity_norm: float
    lever: Reduced | None = None
    reached: tuple[bool, ...] = ()  # per pair: is |lever_p| reached in the box (a whole turn)? (else -|lever_p|)
    turn: float | None = None  # the norm is (a, X, Y), 9 sums: |X cos + Y sin| <= turn


@dataclass(frozen=True, eq=False)
class Maxima:
    """Per objective: a proven upper bound of its maximum, and the best value the boxes'
    centres (or the climbs from them) reached, with its angles theta (-inf and nan where
    none beat the incumbent); and the number of box bounds spent."""

    bound: np.ndarray
    value: np.ndarray
    theta: np.ndarray
    evaluations: int


def certify_maxima(
    objectives, lower, upper, incumbent, tol, polish=None, evaluations: int | None = None, ceiling=None, at=None
) -> Maxima:
    """Upper bounds of the objectives' maxima over theta in [lower, upper] ((n,), or (K, n):
    a box per objective), proven to
    within ``tol`` (K,) of the best value known (``incumbent`` (K,), values at real poses)
    unless the budget of ``evaluations`` box bounds runs out first. Objectives over the same
    joints are searched together; after a first bound of the whole box each, the groups
    take turns of at most SLICE box bounds, so that a hard one cannot starve the others.

    Where a box's centre beats the best value known by more than tol, the search missed a
    maximum there: ``polish(indices, theta)`` (objectives (P,), angles (P, n)) -> (values,
    theta) climbs from it to the real poses' values, which then serve as the best known.
    ``ceiling`` (K,): a box whose bound is at most its objective's ceiling is closed too,
    however the best value moves (a decision: is the maximum below the ceiling?). ``at``
    (K, n): the angles of the incumbents' poses (nan: none), which tell where the norm bound
    is reached (see the module).
    """
    evaluations = EVALUATIONS if evaluations is None else evaluations
    K = len(objectives)
    lower = np.broadcast_to(np.asarray(lower, dtype=float), (K, np.shape(lower)[-1]))
    upper = np.broadcast_to(np.asarray(upper, dtype=float), lower.shape)
    incumbent, tol = np.asarray(incumbent, dtype=float), np.asarray(tol, dtype=float)
    n = lower.shape[1]
    members: dict[tuple, list[int]] = {}
    for k, objective in enumerate(objectives):
        key = (objective.value.dims, objective.norm.dims, objective.lever is None, objective.turn is None)
        members.setdefault(key, []).append(k)
    groups = []
    for ks in members.values():
        ks = np.array(ks)
        climb = None if polish is None else (lambda local, theta, ks=ks: polish(ks[local], theta))
        group = _Group([objectives[k] for k in ks], lower[ks], upper[ks], incumbent[ks], tol[ks], climb)
        if at is not None:
            group.unreached = group.norm_unreached(np.asarray(at, dtype=float)[ks], incumbent[ks])
        if ceiling is not None:
            group.ceiling = np.asarray(ceiling, dtype=float)[ks]
        groups.append((ks, group))
    spent = sum(group.advance(group.boxes) * group.cost for _, group in groups)  # the whole box, whatever the budget
    while spent < evaluations and not out_of_time():
        open_groups = [group for _, group in groups if group.boxes]
        if not open_groups:
            break
        share = max(1.0, min(SLICE, (evaluations - spent) / len(open_groups)))
        for group in open_groups:
            spent += group.advance(max(1, int(share / group.cost))) * group.cost
    bound, value, theta = np.full(K, -np.inf), np.full(K, -np.inf), np.full((K, n), np.nan)
    for ks, group in groups:
        bound[ks], value[ks], theta[ks] = group.result()
    return Maxima(bound, value, theta, int(spent))


class _Group:
    """Objectives over the same joints, searched together: boxes of theta, each with its
    objective (``owner``) and its parent's bound, best first."""

    def __init__(self, objectives, lower, upper, incumbent, tol, polish):
        first = objectives[0]
        self.value_dims, self.norm_dims = list(first.value.dims), list(first.norm.dims)
        self.values = np.array([o.value.coefficients for o in objectives])  # (K, 3^d)
        self.norms = np.array([o.norm.coefficients for o in objectives])  # (K, 3, 3^d')
        g = np.array([o.gravity_norm for o in objectives])
        size = np.abs(self.values).sum(axis=1)
        self.value_slack = np.array([o.value.error for o in objectives]) + rounding(len(self.value_dims)) * size
        norm_size = np.abs(self.norms).sum(axis=(1, 2))
        norm_error = np.array([np.sum(o.norm.error) for o in objectives])
        self.norm_slack = g * (norm_error + rounding(len(self.norm_dims)) * norm_size)
        self.gravity = g * (1 + 8 * U)
        self.turns = None if first.turn is None else np.array([o.turn for o in objectives])
        self.turning = [k for k in self.value_dims if k not in self.norm_dims]  # the joints turning gravity in frame j
        self.unreached = np.zeros(len(objectives), dtype=bool)  # per objective: is the norm not reached?
        self.levers, self.lever_slack = None, np.zeros(len(objectives))
        if first.lever is not None:
            self.levers = np.array([o.lever.coefficients for o in objectives])  # (K, 2 P, 3^d): P pairs
            pairs = self.levers.shape[1] // 2
            self.reached = np.array([[o.reached[p] if o.reached else True for p in range(pairs)] for o in objectives])
            lever_error = np.array([np.sum(o.lever.error) for o in objectives])
            self.lever_slack = lever_error + rounding(len(self.value_dims)) * np.abs(self.levers).sum(axis=(1, 2))
        levers = 0 if self.levers is None else self.levers.shape[1] * 3 ** len(self.value_dims)
        self.cost = max(
            1.0, (3 ** len(self.value_dims) + levers + self.norms.shape[1] * 3 ** len(self.norm_dims)) / TERMS
        )
        K, n = lower.shape
        upper = np.minimum(upper, lower + 2 * math.pi)  # the sums repeat every turn
        self.tol = np.maximum(
            tol, 4 * (self.value_slack + self.lever_slack + self.norm_slack)
        )  # rounding is not to be closed
        self.polish = polish
        self.ceiling = np.full(
            K, np.inf
        )  # a bound at most this closes a box, whatever the best value (see certify_maxima)
        self.lo, self.hi, self.owner = lower.copy(), upper.copy(), np.arange(K)
        self.inherited = np.full(K, np.inf)
        self.best, self.closed = incumbent.copy(), np.full(K, -np.inf)
        self.best_value, self.best_theta = np.full(K, -np.inf), np.full((K, n), np.nan)

    @property
    def boxes(self) -> int:
        return self.owner.size

    def result(self):
        """(bounds, best values the search found, their angles) per objective."""
        bound = np.maximum(self.best, self.closed)
        np.maximum.at(bound, self.owner, self.inherited)
        return bound, self.best_value, self.best_theta

    def advance(self, evaluations: int) -> int:
        """Bound, drop, close or split up to ``evaluations`` boxes, best first; the number done."""
        spent = 0
        while self.owner.size and spent < evaluations:
            if spent and out_of_time():  # (the first batch always: a bound of the whole box)
                break
            lo, hi, owner, inherited, best, tol = self.lo, self.hi, self.owner, self.inherited, self.best, self.tol
            take = min(owner.size, BATCH, evaluations - spent)
            order = np.argsort(-inherited, kind="stable")
            now, later = order[:take], order[take:]
            centre, radius = 0.5 * (lo[now] + hi[now]), 0.5 * (hi[now] - lo[now])
            k = owner[now]
            target = np.maximum(np.minimum(best[k] + tol[k], self.ceiling[k]), best[k])
            bound, value, weight = self._bound(k, centre, radius, target)
            bound = np.where(np.isnan(bound), np.inf, bound)  # (a bound that failed bounds nothing: the box stays)
            spent += take
            self._improve(k, value, centre, best, tol, self.polish, self.best_value, self.best_theta)
            weight = np.where(hi[now] > lo[now], weight, -1.0)  # a joint whose range is a point cannot split
            kept = bound >= best[k]
            done = kept & ((bound <= target) | (weight.max(axis=1) <= 0))  # (nothing to split: as is)
            np.maximum.at(self.closed, k[done], bound[done])
            split = now[kept & ~done]
            axis = np.argmax(weight[kept & ~done], axis=1)
            middle = 0.5 * (lo[split, axis] + hi[split, axis])
            left_hi, right_lo = hi[split].copy(), lo[split].copy()
            rows = np.arange(split.size)
            left_hi[rows, axis], right_lo[rows, axis] = middle, middle
            parent = bound[kept & ~done]
            self.lo = np.concatenate([lo[later], lo[split], right_lo])
            self.hi = np.concatenate([hi[later], left_hi, hi[split]])
            self.owner = np.concatenate([owner[later], owner[split], owner[split]])
            self.inherited = np.concatenate([inherited[later], parent, parent])
        return spent

    @staticmethod
    def _improve(k, value, centre, best, tol, polish, best_value, best_theta):
        """Take the boxes' centres (objectives k) that beat the best values: climbed from by
        ``polish`` where they beat them by more than tol."""
        order = np.argsort(value)  # ascending: per objective the best centre comes last
        top = np.zeros(len(best), dtype=int) - 1
        top[k[order]] = order
        found = np.flatnonzero((top >= 0) & (value[np.maximum(top, 0)] > best))
        if not found.size:
            return
        values, thetas = value[top[found]], centre[top[found]]
        missed = values > best[found] + tol[found]
        if polish is not None and missed.any():
            climbed, climbed_theta = polish(found[missed], thetas[missed])
            higher = climbed > values[missed]
            values[np.flatnonzero(missed)[higher]] = climbed[higher]
            thetas[np.flatnonzero(missed)[higher]] = climbed_theta[higher]
        best[found] = np.maximum(best[found], values)
        best_value[found], best_theta[found] = values, thetas

    def _bound(self, owner, centre, radius, target):
        """Upper bounds over the boxes, a value at each centre (rounded down; -inf where not
        needed) and each joint's weight in the bound (where to split: the norm bound's
        joints only where it could come down to ``target``, the best value known plus tol).
        The bound over fewer joints first, the other only where the first is above target."""
        B, n = centre.shape
        value = np.full(B, -np.inf)
        by_value, by_norm, floor = np.full(B, np.inf), np.full(B, np.inf), np.full(B, np.inf)
        value_weight, norm_weight = np.zeros((B, n)), np.zeros((B, n))
        norm_first = len(self.norm_dims) < len(self.value_dims)
        for part in ("norm", "value") if norm_first else ("value", "norm"):
            rows = np.flatnonzero(np.minimum(by_value, by_norm) > target)
            if not rows.size:
                break
            args = owner[rows], centre[rows], radius[rows], target[rows]
            if part == "value":
                by_value[rows], value[rows], value_weight[rows] = self._value_bound(*args)
            else:
                by_norm[rows], floor[rows], norm_weight[rows] = self._norm_bound(*args)
        use_norm = (by_norm < by_value) & (floor <= target)
        if self.turning:
            away = self._turned_away(owner, centre, radius) if len(self.turning) == 1 else self.unreached[owner]
            use_norm &= ~(away & (radius[:, self.turning] > TURNING).any(axis=1))
        return np.minimum(by_value, by_norm), value, np.where(use_norm[:, None], norm_weight, value_weight)

    def norm_unreached(self, theta, incumbent) -> np.ndarray:
        """Per objective: is its best value known, at angles theta (K, n), below REACHED of
        the norm bound there (the joints up to j could not turn gravity to omega_j)?"""
        known = np.isfinite(theta).all(axis=1) & np.isfinite(incumbent)
        unreached = np.zeros(len(incumbent), dtype=bool)
        if self.turning and known.any():
            rows = np.flatnonzero(known)
            centre = theta[rows]
            norm = self._norm_bound(rows, centre, np.zeros_like(centre), np.full(rows.size, np.inf))[1]
            unreached[rows] = incumbent[rows] < REACHED * norm
        return unreached

    def _turned_away(self, owner, centre, radius) -> np.ndarray:
        """Per box, where one joint t alone turns gravity in frame j (on a circle): is the
        angle of t that turns it to omega_j, at the box's centre, outside the box's range of
        t? The value there is A + X cos(theta_t) + Y sin(theta_t), the other joints at the
        centre; that angle is atan2(Y, X)."""
        B, dims, t = len(owner), self.value_dims, self.turning[0]
        p = dims.index(t)
        C = np.moveaxis(self.values[owner].reshape((B,) + (3,) * len(dims)), p + 1, -1).reshape(B, -1, 3)
        _, X, Y = np.einsum("ba,bak->kb", basis(centre[:, [k for k in dims if k != t]]), C)
        best = np.arctan2(Y, X)
        lo, hi = centre[:, t] - radius[:, t], centre[:, t] + radius[:, t]
        turns = np.ceil((lo - best) / (2 * math.pi))
        return best + 2 * math.pi * turns > hi

    def _value_bound(self, owner, centre, radius, target):
        """The value's own bound over the boxes, its value at the centres (rounded down),
        and the joints' weights in it."""
        B, n = centre.shape
        d = self.value_dims
        D = expand(self.values[owner], centre[:, d])
        W, sigma = sizes(radius[:, d]), sizes_of_s(radius[:, d])
        g, Q, high, terms = model(D, W, radius[:, d])
        base = D[:, 0] + high + self.value_slack[owner]
        value = D[:, 0] - self.value_slack[owner]
        if self.levers is None:
            bound = base + quadratic_max(g, Q, sigma, enough=target - base)
        else:
            bound, at_centre, lever_terms = self._lever_bound(
                owner, centre[:, d], radius[:, d], W, sigma, (g, Q, base), target
            )
            value = value + at_centre - self.lever_slack[owner]
            terms = terms + lever_terms
        weight = np.zeros((B, n))
        weight[:, d] = terms @ layout(len(d)).involves
        return bound, value, weight

    def _lever_bound(self, owner, centre, radius, W, sigma, value_model, target):
        """Bounds of value + sum of |v_p| over the boxes, v_p = (X_p, Y_p) the levers, given
        the value's quadratic model (g, Q; the rest ``base``); the sum at the centres; the
        size of the levers' terms.

        |v|^2 <= M(s), a quadratic model (``bounds.squared_model``). For any a > 0, |v| <= a / 2
        + |v|^2 / (2 a) (equal where |v| = a): with a = |v(centre)| the bound is one model,
        exact to first order, maximised with the value's. Also, where that one is above
        its target: value's bound + sum of sqrt(max M_p)."""
        B, d = centre.shape
        g, Q, base = value_model
        pairs = self.levers.shape[1] // 2
        N = expand(self.levers[owner], centre).reshape(B, pairs, 2, -1)
        models = [squared_model(N[:, p], W, sigma, radius) for p in range(pairs)]
        reached = np.where(self.reached[owner], 1.0, -1.0)  # (a value at the centres: a real one, or below)
        at_centre = sum(m[0] * reached[:, p] for p, m in enumerate(models))
        lever_terms = sum(m[4] for m in models)
        constant, g_all, Q_all, room = base + self.lever_slack[owner], g.copy(), Q.copy(), np.abs(base)
        for size, squared, g_v, Q_v, _ in models:
            a = np.maximum(size, 1e-150)
            k = 0.5 / a
            constant = constant + 0.5 * a + k * squared
            g_all, Q_all = g_all + 2 * k[:, None] * g_v, Q_all + 2 * k[:, None, None] * Q_v
            room = room + a + k * np.abs(squared)
        room = 1e-12 * room
        enough = target - constant - room - 1e-12 * np.abs(target)
        bound = constant + quadratic_max(g_all, Q_all, sigma, enough)
        bound = bound + room + 1e-12 * np.abs(bound)
        rows = np.flatnonzero(~(bound <= target))
        if rows.size:  # (the value's model and each lever's in one stack)
            stack_g = np.concatenate([g[rows]] + [2 * m[2][rows] for m in models])
            stack_Q = np.concatenate([Q[rows]] + [2 * m[3][rows] for m in models])
            tops = quadratic_max(stack_g, stack_Q, np.tile(sigma[rows], (1 + pairs, 1))).reshape(1 + pairs, -1)
            second = base[rows] + tops[0] + self.lever_slack[owner[rows]]
            for (_, squared, _, _, _), top in zip(models, tops[1:]):
                norm_max = squared[rows] + top
                second = second + np.sqrt(np.maximum(norm_max, 0.0)) * (1 + 1e-12)
            bound[rows] = np.fmin(bound[rows], second + room[rows] + 1e-12 * np.abs(second))  # (nan: the other)
        return bound, at_centre - 1e-12 * sum(m[0] for m in models), lever_terms

    def _norm_bound(self, owner, centre, radius, target):
        """|tau_j| <= |g| |omega_j| over the boxes, |g| |omega_j| at the centres, and the
        joints' weights in it (|omega_j|^2 by its quadratic model, ``bounds.squared_model``)."""
        B, n = centre.shape
        e = self.norm_dims
        N = expand(self.norms[owner], centre[:, e])
        W, sigma = sizes(radius[:, e]), sizes_of_s(radius[:, e])
        gravity, slack = self.gravity[owner], self.norm_slack[owner]
        enough = ((target - slack) / gravity) ** 2  # |omega|^2 that would do
        if self.turns is None:
            size, base, g, Q, terms = squared_model(N, W, sigma, radius[:, e])
            squared = base + quadratic_max(2 * g, 2 * Q, sigma, enough - base)
        else:  # (the payload's direction not an angle: see ``bounds.turned_squared_max``)
            size, squared, terms = turned_squared_max(N, W, sigma, radius[:, e], self.turns[owner], enough)
        bound = gravity * np.sqrt(np.maximum(squared, 0.0)) * (1 + 4 * U) + slack
        weight = np.zeros((B, n))
        weight[:, e] = terms @ layout(len(e)).involves
        return bound, gravity * size, weight
