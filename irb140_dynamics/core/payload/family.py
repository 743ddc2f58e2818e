"""A payload's shape at any mass: torques affine in the mass, and their proven worst values.

Units: kg, m, rad, N m. A payload is a RigidBody on the flange (frame n); it replaces the
model's own payload. For a fixed CoM and inertia the torques are affine in the payload
mass m,

    tau(m) = tau0 + m dtau,

so at one state each joint allows an interval of masses (|tau_j(m)| <= L_j), exactly.

The worst static torques over the joint ranges come in two halves: the search of
``workspace`` (sampling and exact coordinate ascent) finds poses and their torques, the
branch and bound of ``certify`` proves how far above them the true maxima can be (the
gap; CERTIFY_RTOL of the torque when it closes, always within the budget of
``certify.EVALUATIONS`` box bounds per proof). Models beyond harmonic.MAX_JOINTS joints
get plain interval bounds within the budget of ``interval_bounds.interval_maxima``. Proofs are
remembered per payload mass and joint ranges, families per arm and payload shape; a proof
the analysis' deadline cut short (see ``stop``) is not remembered.
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from dataclasses import dataclass, fields, replace
from functools import cached_property

import numpy as np

from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.core.dynamics import gravity_batch, rnea
from irb140_dynamics.core.model.rigid_body import RigidBody
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.payload.proof import certify
from irb140_dynamics.core.payload.proof.certify import Objective, certify_maxima
from irb140_dynamics.core.payload.proof.harmonic import NOISE, HarmonicSum, StaticForms, without_wrist
from irb140_dynamics.core.payload.proof.interval_bounds import interval_maxima
from irb140_dynamics.core.payload.stop import ran_out
from irb140_dynamics.core.payload.workspace import JointRanges
from irb140_dynamics.core.scalars.interval import Interval, bounds_of

RTOL = 1e-9  # a torque within RTOL of its limit is within it
CERTIFY_RTOL = 5e-10  # the gap the proof aims at, relative to the torque (half of RTOL)
UNLOADED = 1e-12  # N m (N) per kg: a payload's torque on a joint below this is rounding noise (a lever of 1e-13 m)


@dataclass(frozen=True, eq=False)
class Extremes:
    """max tau_j (row j) and max -tau_j (row n + j) over the joint ranges: the best value
    found at a pose (a real torque there), the pose, and a proven upper bound."""

    values: np.ndarray  # (2n,)
    poses: np.ndarray  # (2n, n) rad
    bounds: np.ndarray  # (2n,), >= values
    tree_poses: np.ndarray | None = None  # (2n, n_tree): on a tree, the whole tree's poses (path.widened)

    def largest(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per joint the signed torque of largest magnitude found, its pose, and a proven
        bound of the magnitude over the ranges: (n,), (n, n), (n,)."""
        n, values, bounds = self.values.size // 2, self.values, self.bounds
        positive = self._positive()
        torque = np.where(positive, values[:n], -values[n:])
        pose = np.where(positive[:, None], self.poses[:n], self.poses[n:])
        return torque, pose, np.maximum(np.maximum(bounds[:n], bounds[n:]), np.abs(torque))

    def largest_tree_pose(self) -> np.ndarray | None:
        """Per joint the whole tree's pose of ``largest``'s torque, (n, n_tree); None on a chain."""
        if self.tree_poses is None:
            return None
        n = self.values.size // 2
        return np.where(self._positive()[:, None], self.tree_poses[:n], self.tree_poses[n:])

    def _positive(self) -> np.ndarray:
        """Per joint: +tau_j is the larger in size (a tie goes to +tau_j)."""
        n, values = self.values.size // 2, self.values
        return values[:n] >= values[n:] - RTOL * np.max(np.abs(values))


@dataclass(frozen=True, eq=False)
class PayloadFamily:
    """The model carrying one payload (CoM, inertia) at any mass m: tau(m) = tau0 + m dtau."""

    empty: RobotModel  # the payload at 0 kg
    unit: RobotModel  # the payload at 1 kg
    given_forms: tuple[StaticForms, StaticForms] | None = None  # the forms, if already known
    direction: int | None = None  # the last joint, if it turns the payload's CoM about the flange axis (a whole turn)

    def torques(self, q, qd) -> tuple[np.ndarray, np.ndarray]:
        """(tau0, dtau) [N m, N m/kg] that hold the motion (q, qd) with qdd = 0."""
        qdd = np.zeros(self.empty.n)
        tau0 = rnea(self.empty, q, qd, qdd)
        return tau0, rnea(self.unit, q, qd, qdd) - tau0

    def static_torques(self, Q) -> tuple[np.ndarray, np.ndarray]:
        """(G0, dG): the gravity torques at poses Q (N, n), as tau0 and dtau."""
        G0 = gravity_batch(self.empty, Q)
        return G0, gravity_batch(self.unit, Q) - G0

    def static_torque(self, m: float):
        """Q -> the gravity torques at poses Q with the payload at m kg."""

        def torque(Q):
            G0, dG = self.static_torques(Q)
            return G0 + m * dG

        return torque

    def search(self, m: float, ranges: JointRanges, sample_torques=None, warm=None):
        """The search alone: max +-tau_j at m kg, (values (2n,), poses (2n, n))."""
        n = self.empty.n
        return ranges.maximize(self.static_torque(m), np.vstack([np.eye(n), -np.eye(n)]), sample_torques, warm)

    def extremes(
        self,
        m: float,
        ranges: JointRanges,
        sample_torques=None,
        warm=None,
        rows=None,
        share: float = 1.0,
        found=None,
        ceiling=None,
    ) -> Extremes:
        """The worst static torques at m kg, searched and proven (remembered per m and
        ranges): all 2n of them, or only ``rows`` proven (the others' bounds inf), within
        ``share`` of the proof's budget; ``found``: (values, poses) of a search at m done.
        ``ceiling`` (2n,): a row's proof may stop once its bound is below it (a limit to
        prove, not the maximum itself: far cheaper where the maximum is well below it)."""
        rows = np.arange(2 * self.empty.n) if rows is None else np.asarray(rows, dtype=int)
        ceiling = None if ceiling is None else np.asarray(ceiling, dtype=float)
        key = (float(m), ranges.lower.tobytes(), ranges.upper.tobytes(), rows.tobytes())
        key += (None if ceiling is None else ceiling.tobytes(),)
        proven = self._proven.get(key)  # (a family may serve several threads: no check-then-get)
        if proven is not None:
            return proven
        values, poses = self.search(m, ranges, sample_torques, warm) if found is None else found
        proven = self._prove(m, ranges, values, poses, rows, share, ceiling)
        if not ran_out():  # cut short by the deadline: not the proof the budget would give
            if len(self._proven) >= 8:
                self._proven.pop(next(iter(self._proven)))
            self._proven[key] = proven
        return proven

    @cached_property
    def _proven(self) -> dict:
        return {}

    @cached_property
    def _off_axis(self) -> float:
        """l [m]: the payload's CoM off the flange's z axis (the offset ``direction`` turns)."""
        return math.hypot(*self.unit.payload.com[:2])

    @cached_property
    def forms(self) -> tuple[StaticForms, StaticForms] | None:
        """The harmonic forms of the payload at 0 and 1 kg (None for too many joints)."""
        if self.given_forms is not None:
            return self.given_forms
        empty = StaticForms.of(self.empty)
        return None if empty is None else (empty, StaticForms.of(self.unit))

    def _prove(self, m, ranges, values, poses, rows, share, ceiling=None) -> Extremes:
        n, torque = self.empty.n, self.static_torque(m)
        bounds = np.full(2 * n, np.inf)
        weights = np.vstack([np.eye(n), -np.eye(n)])
        offsets = np.array([0.0 if a is None else a for a in kernels_of(self.empty).angles])
        scale = max(1.0, float(np.max(np.abs(values))))
        tol = CERTIFY_RTOL * np.maximum(np.abs(values), 1e-3 * scale)
        if ceiling is not None:
            tol = np.maximum(tol, np.nan_to_num(ceiling - values, posinf=np.inf, neginf=0.0))
        lower, upper = ranges.lower + offsets, ranges.upper + offsets
        joints, signs = rows % n, np.where(rows < n, 1.0, -1.0)
        if self.forms is None:
            bounds[rows] = interval_maxima(
                self._interval_torques(m, offsets), joints, signs, ranges.lower, ranges.upper, values[rows], tol[rows]
            )
            return Extremes(values, poses, bounds)
        forms = self.forms[0].affine(self.forms[1], m)
        sliding = np.array([cr is not None for cr in forms.sliding], dtype=bool)
        lower = np.where(sliding, np.maximum(forms.angles_of(lower) - 1e-12, -np.pi / 2), lower)  # (rounding: wider)
        upper = np.where(sliding, np.minimum(forms.angles_of(upper) + 1e-12, np.pi / 2), upper)

        def joints_of(theta):  # joint values q of angles theta (prismatic: their displacements)
            return np.clip(forms.joints_of(theta) - offsets, ranges.lower, ranges.upper)

        objectives = [
            self._objective(forms, j, s, m, found, room)
            for j, s, found, room in zip(joints, signs, values[rows], tol[rows])
        ]
        boxes = [objective.norm.box(*objective.value.box(lower, upper)) for objective in objectives]

        def angles(k, theta):  # the joint angles of objective k's box (parallel joints merged: before j, after j)
            joined = [(objectives[i], objectives[i].norm.angles(t, lower, upper)) for i, t in zip(k, theta)]
            return np.array([objective.value.angles(t, lower, upper)[0] for objective, t in joined])

        def folded(k, pose):  # the angles of objective k's box at joint values q (P, n)
            at = [
                objectives[i].norm.fold(objectives[i].value.fold(t)) for i, t in zip(k, forms.angles_of(pose + offsets))
            ]
            return np.array([t[0] for t in at])

        def polish(k, theta):
            found, pose = ranges.climb(torque, weights[rows[k]], joints_of(angles(k, theta)))
            return found, folded(k, pose)

        proof = certify_maxima(
            objectives,
            np.array([b[0] for b in boxes]),
            np.array([b[1] for b in boxes]),
            values[rows],
            tol[rows],
            polish,
            int(share * certify.EVALUATIONS),
            None if ceiling is None else ceiling[rows],
            folded(range(rows.size), poses[rows]),
        )
        bounds[rows] = proof.bound
        values, poses = values.copy(), poses.copy()
        better = np.flatnonzero(proof.value > values[rows])
        found = rows[better]
        if found.size:  # the search missed these maxima: take the real poses' torques
            pose = joints_of(angles(better, proof.theta[better]))
            value = np.einsum("kn,kn->k", torque(pose), weights[found])
            higher = value > values[found]
            values[found[higher]], poses[found[higher]] = value[higher], pose[higher]
        return Extremes(values, poses, np.maximum(bounds, values))

    def _objective(
        self, forms: StaticForms, j: int, sign: float, m: float, found: float = 0.0, room: float = 0.0
    ) -> Objective:
        """+-tau_j at m kg as the proof's objective; with a ``direction`` joint, its worst
        value over the directions: A + |(X, Y)| (see ``Objective``), not one more angle;
        and without the last joint where it only turns the CoM about the flange axis (see
        ``harmonic.without_wrist``: a lever more); its norm without the direction too
        where that bound, off by at most (|g| m l)^2 / (2 |tau_j|) at poses where the CoM's
        offset l cannot turn fully outward, is off by at most the ``room`` [N m] the proof
        has above the torque ``found`` (see ``_norm``; else the norm with the direction as
        an angle serves better)."""
        torque, omega = forms.torque[j] * sign, forms.omega[j]
        if self.direction is None or j == self.direction:
            return Objective(torque.reduced(merge=True), omega.reduced(), forms.gravity_norm)
        parts = torque.over_direction()
        if parts.dims and parts.dims[-1] == self.direction - 1:
            parts = without_wrist(parts) or parts
        reached = (False, True) if parts.coefficients.lo.shape[0] == 5 else (True,)  # ((P, Q): the wrist's turn)
        parts = parts.reduced(merge=True)
        value = replace(parts, coefficients=parts.coefficients[0], error=parts.error[0])
        size = np.abs(parts.coefficients).sum(axis=1)
        noise = NOISE * size.sum()  # (a pair of rounding noise: a CoM on the axis)
        pairs = [p for p in range(parts.error.size // 2) if size[1 + 2 * p : 3 + 2 * p].sum() > noise]
        keep = [1 + 2 * p + k for p in pairs for k in (0, 1)]
        dropped = np.delete(np.arange(1, parts.error.size), np.array(keep, dtype=int) - 1)
        vanished = float(np.sum(parts.error[dropped]) + np.sum(size[dropped]))  # |(X, Y)| <= |X| + |Y|
        value = replace(value, error=value.error + vanished)
        lever = replace(parts, coefficients=parts.coefficients[keep], error=parts.error[keep]) if keep else None
        reached = tuple(reached[p] for p in pairs)
        offset = m * self._off_axis * forms.gravity_norm  # N m: |g| m l
        norm, turn = self._norm(omega, m, turned=offset**2 <= 2 * room * abs(found))
        if any(a in value.dims or b in value.dims for a, b, _ in norm.merges):  # (their box is the value's too)
            norm, turn = self._norm(omega, m, merge=False, turned=turn is not None)
        return Objective(value, norm, forms.gravity_norm, lever, reached, turn)

    def _norm(self, omega, m: float, merge: bool = True, turned: bool = True):
        """omega_j as the proof's norm: with the direction as an angle (merged with a wrist
        it turns with), or, ``turned``, without it: (a, X, Y) (9 sums), omega = a + X cos(phi)
        + Y sin(phi), and the most |X cos + Y sin| can be (``Objective.turn``).

        That part is the payload's offset l off the flange axis turned by phi: per unit of
        gravity a mass m at p loads joint j by m (z_j x p), so it is m l (z_j x u) for a unit
        vector u, at most m l, exactly (plus the sums' errors). A wrist b that turns the
        offset about the flange axis turns (X, Y) only (X + iY = exp(+-i theta_b) (X0 + iY0),
        ``harmonic.without_wrist``): over a whole turn of phi, (X0, Y0) serve, and b is left
        in a alone (its own link's CoM). Turned, the norm is over two angles fewer, and its
        bound is exact at poses where the offset turns fully outward (see
        ``bounds.turned_squared_max``)."""
        if not turned or not omega.dims or omega.dims[-1] != self.direction:
            return (omega.reduced(merge=True) if merge else omega.reduced()), None
        parts = omega.over_direction()  # (3 parts, 3 axes, ...)
        c = parts.coefficients
        lo, hi = c.lo.reshape(3, 3, -1), c.hi.reshape(3, 3, -1)
        folded = without_wrist(parts) if parts.dims and parts.dims[-1] == self.direction - 1 else None
        if folded is not None:  # X + iY = exp(+-i theta_b) (X0 + iY0): (X0, Y0) serve, b turns them with phi
            kept = folded.coefficients  # (5, 3 axes x 3^(d-1)): A0, P, Q, X0, Y0
            lo, hi = lo.copy(), hi.copy()
            lo[1:], hi[1:] = 0.0, 0.0
            lo[1:, :, ::3] = kept.lo[3:].reshape(2, 3, -1)
            hi[1:, :, ::3] = kept.hi[3:].reshape(2, 3, -1)
        stacked = HarmonicSum(parts.dims, Interval(lo.reshape(9, -1), hi.reshape(9, -1)))
        norm = stacked.reduced(merge=merge)
        turn = abs(float(m)) * self._off_axis * (1 + 1e-9) + float(np.sum(norm.error[3:]))
        return norm, turn

    def _interval_torques(self, m, offsets):
        """(lo, hi) per joint (n, B) of the static torques at m kg over boxes of q (B, n)."""
        model = self.empty.with_payload(RigidBody(m, self.empty.payload.com, self.empty.payload.inertia))
        links, gravity, n = kernels_of(model).links, kernels_of(model).gravity, model.n

        def evaluate(lo, hi):
            theta = [Interval(lo[:, k], hi[:, k]) + offsets[k] for k in range(n)]
            cs = [(t,) if link.prismatic else (t.cos(), t.sin()) for t, link in zip(theta, links)]
            tau = algorithms.rnea(links, cs, [0.0] * n, [0.0] * n, gravity)
            pairs = [bounds_of(t, len(lo)) for t in tau]
            return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])

        return evaluate


def payload_family(model: RobotModel, payload: RigidBody) -> PayloadFamily:
    """``payload``'s shape at any mass on ``model`` (whatever payload ``model`` carries; its
    flange and everything else kept).

    Built once per arm and shape (the last FAMILIES remembered): the two models validate
    the CoM and inertia (ModelError naming ``payload.com`` or ``payload.inertia``) and
    compile their kernels then. Prismatic joints too: the proof takes their displacements
    as angles (see ``harmonic.slide``).
    """
    if not model.is_chain:  # the proofs slice the chain (harmonic): a tree's would be wrong
        raise ValueError(
            "the payload analysis takes a serial chain without mimic joints: load the URDF with its tip_link"
        )
    arm = tuple(getattr(model, f.name) for f in fields(model) if f.name != "payload")
    key = (arm, tuple(payload.com), tuple(payload.inertia))
    with _LOCK:
        family = _FAMILIES.get(key)
    if family is None:

        def carrying(mass):
            return replace(model, payload=RigidBody(mass, payload.com, payload.inertia))

        family = PayloadFamily(carrying(0.0), carrying(1.0))
        with _LOCK:
            family = _FAMILIES.setdefault(key, family)
            while len(_FAMILIES) > FAMILIES:
                _FAMILIES.popitem(last=False)
    return family


def forget_families() -> None:
    """Forget the families built (and so their proofs)."""
    with _LOCK:
        _FAMILIES.clear()


FAMILIES = 16
_FAMILIES: OrderedDict = OrderedDict()
_LOCK = threading.Lock()


def mass_bounds(tau0, dtau, limits) -> tuple[np.ndarray, np.ndarray]:
    """Per joint, the payload masses m with |tau0 + m dtau| <= L: (lower, upper) [kg].

    Works on (..., n) arrays; L = inf is no limit. An empty interval has lower > upper.
    A dtau_j below 1e-12 of the largest, or below UNLOADED, is rounding noise: the payload
    does not load joint j.
    """
    tau0, dtau, L = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (tau0, dtau, limits)))
    noise = np.maximum(1e-12 * np.max(np.abs(dtau), axis=-1, keepdims=True), UNLOADED)
    dtau = np.where(np.abs(dtau) <= noise, 0.0, dtau)
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = (-L - tau0) / dtau, (L - tau0) / dtau
    fits = np.abs(tau0) <= L
    lower = np.where(dtau == 0, np.where(fits, -np.inf, np.inf), np.minimum(a, b))
    upper = np.where(dtau == 0, np.where(fits, np.inf, -np.inf), np.maximum(a, b))
    return lower, upper


def max_mass(tau0, dtau, limits) -> tuple[np.ndarray, np.ndarray]:
    """The largest payload mass m >= 0 keeping every joint within its limit, and the joint
    that bounds it (index; the first if several do), for torques (..., n).

    nan if no m >= 0 fits (the joint is then one that fails); inf if no joint bounds it.
    """
    lower, upper = mass_bounds(tau0, dtau, limits)
    m = np.min(upper, axis=-1)
    joint = np.argmax(at_most(upper, m[..., None]), axis=-1)
    fits = np.maximum(0.0, np.max(lower, axis=-1)) <= m
    return np.where(fits, m, np.nan), joint


def loads(torque) -> np.ndarray:
    """Per joint: is the (worst) static torque more than rounding noise, i.e. does the load
    reach the joint at all? Noise: RTOL of the largest finite one, or of 1 N m; an infinite
    bound (a proof not even begun: out of time) loads: it may."""
    worst = np.abs(torque)
    finite = worst[np.isfinite(worst)]
    return worst > RTOL * max(finite.max(initial=0.0), 1.0)


def at_most(x, m):
    """x <= m, a value within RTOL of m counting as equal to it."""
    with np.errstate(invalid="ignore"):
        return (x <= m) | (x <= m + RTOL * np.abs(m))
