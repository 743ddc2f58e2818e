"""Payload analysis: joint torque limits from the rated payload, the worst static load of a
payload over the joint ranges, and the largest payload a pose or the whole workspace holds.

Units: kg, m, rad, N m. A payload is a RigidBody on the flange (frame n); it replaces the
model's own payload. Its torques are affine in its mass (see ``payload_family``), so the
largest payload is exact, no trial and error: at one state each joint allows an interval
of masses (|tau_j(m)| <= L_j); over the workspace Dinkelbach's iteration finds it (the
worst poses at mass m allow a mass <= m; repeat at that mass until it stops falling).

Worst static torques are proven, not only searched: each comes with an upper bound over
the whole joint box (branch and bound, see ``certify``). Where the budget (or the analysis'
time, see ``stop``) runs out before the bound meets the torque found (the gap), the true
worst torque lies between the two: the verdicts of ``check`` say "unproven" where that
gap straddles a limit. The largest payload over the workspace is proven the same way at
its final mass; if a gap is left there, the mass reported is one the bounds prove, and
``MaxPayload.gap`` how much more the workspace might hold.

The permissible torques follow the report (section 10): the torques of the rated payload,
6 kg at the flange origin, in the pose that loads each joint most. A given torque limit
(``Joint.torque_limit`` > 0) always overrides.

Cost: a first check_payload compiles the kernels and proves the limits and the payload's
workspace load; later ones reuse the proofs (remembered per payload shape and mass). A
payload whose proofs spend their budget (see ``certify``; the largest payload's proof with
MASS_PROOF_SHARE of it), such as 3 kg off the flange axis, takes longest. Figures:
docs/benchmarks.md.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.model.rigid_body import MAX_MASS, ModelError, RigidBody, checked_body
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.model.states import real_numbers, state
from irb140_dynamics.core.payload.family import RTOL, Extremes, PayloadFamily, at_most, loads, max_mass, payload_family
from irb140_dynamics.core.payload.path import payload_path
from irb140_dynamics.core.payload.stop import out_of_time, ran_out
from irb140_dynamics.core.payload.workspace import JointRanges

RATED_PAYLOAD = RigidBody(6.0)  # the IRB-140's rated payload: 6 kg at the flange origin
_PROOF_ROUNDS = 4  # Dinkelbach restarts from poses the proof finds worse than the search did
MASS_PROOF_SHARE = 1 / 3  # of the proof's budget for the largest payload (a gap only lowers it a little)

__all__ = [
    "RATED_PAYLOAD",
    "RTOL",
    "MaxPayload",
    "TorqueLimits",
    "WorkspaceLoad",
    "derive_torque_limits",
    "loads",
    "max_payload_at",
    "payload_family",
    "workspace_load",
]


@dataclass(frozen=True, eq=False)
class MaxPayload:
    """The largest payload mass [kg] proven to hold (nan: none; inf: unbounded), the joint
    at its limit there (index; None if unbounded), the pose q [rad] where that happens, and
    ``gap``: how much more the workspace might hold where the proof's budget ran out first."""

    mass: float
    joint: int | None
    q: np.ndarray | None
    gap: float = 0.0


def _max_payload(m: float, joint: int, q, gap: float = 0.0) -> MaxPayload:
    if m == math.inf:
        return MaxPayload(m, None, None)
    return MaxPayload(m, joint, np.asarray(q, dtype=float), gap)


@dataclass(frozen=True, eq=False)
class TorqueLimits:
    """Joint torque limits [N m] (inf: none), where each comes from, and the rated payload's
    worst static torque per joint with its pose (row j for joint j) and its proven bound."""

    values: tuple[float, ...]
    source: tuple[str, ...]  # "given", "derived" or "none"
    rated_payload: RigidBody
    rated_torque: np.ndarray  # (n,) N m, signed
    rated_pose: np.ndarray  # (n, n) rad
    rated_bound: np.ndarray  # (n,) N m: |rated torque| <= this in every pose (inf: not needed, a given limit)
    out_of_time: bool = False  # the analysis' deadline cut the search and proofs short

    @property
    def highest(self) -> np.ndarray:
        """The largest each limit may be (n,) N m: a derived limit is the rated payload's
        worst torque found, which its proof only bounds (the same where the proof closed)."""
        return np.where(np.array(self.source) == "derived", np.maximum(self.values, self.rated_bound), self.values)

    def reason(self, j: int) -> str:
        """Why joint j has its limit, in words."""
        rated = self.rated_payload
        com = "(" + ", ".join(f"{v:.3f}" for v in rated.com) + ")"
        return {
            "given": "given (torque_limit)",
            "derived": f"worst static torque of the rated payload, {rated.mass:.3f} kg at {com} m",
            "none": "none: the rated payload cannot load it",
        }[self.source[j]]


@dataclass(frozen=True, eq=False)
class WorkspaceLoad:
    """A payload's worst static torque per joint over the joint ranges and its pose (row j
    for joint j), a proven bound of its size, and the largest payload of its shape that
    every pose holds."""

    payload: RigidBody
    torque: np.ndarray  # (n,) N m, signed: found at ``pose``
    pose: np.ndarray  # (n, n) rad
    max_payload: MaxPayload
    bound: np.ndarray  # (n,) N m: |tau_j| <= bound_j in every pose
    out_of_time: bool = False  # the analysis' deadline cut the search and proofs short
    rest: np.ndarray | float = 0.0  # (n,) N m of the bound: the rest of a tree's poses, bounded (path.slack)
    tree_pose: np.ndarray | None = None  # (n, n_tree): on a tree, the whole tree's state of each joint's worst pose
    rest_pose: tuple[str, ...] = ()  # per joint, the rest of the tree in its worst pose, in words (path.rest_poses)

    @property
    def gap(self) -> np.ndarray:
        """How far the worst torques might exceed those found (0 once proven) [N m]."""
        return self.bound - np.abs(self.torque)


# -- the limits -----------------------------------------------------------------------------------


def derive_torque_limits(model: RobotModel, rated_payload: RigidBody = RATED_PAYLOAD) -> TorqueLimits:
    """Each joint's limit: its given torque_limit if > 0, else the worst static torque of
    the rated payload over the joint ranges (the torque found, at a real pose); none (inf)
    for a joint it cannot load (proven). The rated payload's torques are searched for every
    joint, proven for those without a given limit. On a tree, the joints up to the
    payload's link, with the rest of the tree in its worst pose (see ``path``)."""
    rated_payload = checked_body("rated_payload", rated_payload)
    path = payload_path(model)
    model = path.chain
    family = payload_family(model, rated_payload)
    given = np.array(model.torque_limits) > 0
    rows = np.flatnonzero(~np.tile(given, 2))  # a given limit needs no proof
    load = family.extremes(rated_payload.mass, JointRanges.of(model), rows=rows)
    torque, pose, bound = path.widened(rated_payload, load).largest()
    loaded = loads(np.where(given, 0.0, bound))
    source = np.where(given, "given", np.where(loaded, "derived", "none"))
    limits = np.where(given, model.torque_limits, np.where(loaded, np.abs(torque), np.inf))
    return TorqueLimits(tuple(limits.tolist()), tuple(source.tolist()), rated_payload, torque, pose, bound, ran_out())


def limit_values(limits: TorqueLimits | Sequence[float], n: int) -> np.ndarray:
    """The limits as n numbers >= 0 (inf: none), or ValueError naming ``limits``."""
    values = real_numbers(limits.values if isinstance(limits, TorqueLimits) else limits, n, "limits")
    if not (values >= 0).all():  # NaN too: a NaN limit would pass every payload
        raise ValueError(f"limits: must be >= 0 N m (inf: none), got {values.tolist()}")
    return values


# -- the largest payload -------------------------------------------------------------------------


def max_payload_at(model: RobotModel, payload: RigidBody, limits, q, qd=None) -> MaxPayload:
    """The largest mass of ``payload``'s shape that the state (q, qd), qdd = 0, can hold."""
    path = payload_path(model)
    payload, L = checked_body("payload", payload), limit_values(limits, path.chain.n)
    q = state(q, model.n, "q")
    qd = [0.0] * model.n if qd is None else state(qd, model.n, "qd")
    tau0, dtau = path.torques(payload, q, qd)
    return max_payload_here(tau0, dtau, L, np.asarray(q, dtype=float)[path.columns])


def max_payload_here(tau0, dtau, L, q) -> MaxPayload:
    m, joint = max_mass(tau0, dtau, L)
    return _max_payload(float(m), int(joint), q)


def smallest_max_payload(family: PayloadFamily, poses: np.ndarray, L: np.ndarray, G0=None, dG=None) -> MaxPayload:
    """The least of the largest static payloads of poses (N, n) (nan if one holds none);
    of tied poses the one whose limiting joint comes first. (G0, dG): their static
    torques, if known."""
    m, joint = max_mass(*(family.static_torques(poses) if G0 is None else (G0, dG)), L)
    if np.isnan(m).any():
        i = int(np.argmax(np.isnan(m)))
    else:
        i = int(np.argmin(np.where(at_most(m, m.min()), joint, joint.size + m.size)))
    return _max_payload(float(m[i]), int(joint[i]), poses[i])


def workspace_load(
    model: RobotModel,
    payload: RigidBody,
    limits: TorqueLimits | Sequence[float],
    ranges: JointRanges | None = None,
) -> WorkspaceLoad:
    """The payload's worst static torques over the joint ranges (found and proven), and the
    largest payload of its shape that holds still within the limits in every pose.
    Depends only on its arguments: cache it. On a tree, the joints up to the payload's link
    (see ``path``; ``ranges`` theirs), with the rest of the tree in its worst pose: the
    largest payload is proven within each limit less the ``slack`` of the rest's poses."""
    path = payload_path(model)
    model = path.chain
    payload, L = checked_body("payload", payload), limit_values(limits, model.n)
    ranges = JointRanges.of(model) if ranges is None else ranges
    family = payload_family(model, payload)
    G0, dG = family.static_torques(ranges.samples)
    load = family.extremes(payload.mass, ranges, G0 + payload.mass * dG)
    widened = path.widened(payload, load)
    torque, pose, bound = widened.largest()
    best = _workspace_max_payload(family, ranges, np.maximum(L - path.slack, 0.0), G0, dG, payload.mass, load)
    tree_pose, rest_pose = widened.largest_tree_pose(), path.rest_poses(widened)
    return WorkspaceLoad(payload, torque, pose, best, bound, ran_out(), path.slack, tree_pose, rest_pose)


def _workspace_max_payload(family, ranges, L, G0, dG, own_mass: float, load: Extremes) -> MaxPayload:
    """Dinkelbach from the payload's worst poses, then the proof at the mass found; where
    the proof finds a worse pose, Dinkelbach goes on from it."""
    poses = load.poses
    limited = np.flatnonzero(np.isfinite(np.tile(L, 2)))  # the rows of +-tau_j that matter
    best = smallest_max_payload(family, poses, L)
    if best.mass == math.inf:  # no limited joint loaded there: try where the payload loads them most
        _, poses = _most_loaded(family, ranges, dG)
        best = smallest_max_payload(family, poses, L)
    for round_ in range(_PROOF_ROUNDS):
        found, searched = None, math.nan
        while math.isfinite(best.mass) and not out_of_time():  # Dinkelbach
            found, searched = family.search(best.mass, ranges, G0 + best.mass * dG, warm=poses), best.mass
            poses = found[1]
            candidate = smallest_max_payload(family, poses, L)
            if not _lighter(candidate, best):
                break
            best = candidate
        if math.isnan(best.mass):
            return best  # a real pose the arm cannot hold even empty
        m = min(best.mass, MAX_MASS)  # beyond the sanity cap no mass is valid anyway
        found = found if m == searched else None  # the last search was at that mass
        proven = family.extremes(m, ranges, G0 + m * dG, warm=poses, rows=limited, share=MASS_PROOF_SHARE, found=found)
        candidate = smallest_max_payload(family, proven.poses, L)
        if not _lighter(candidate, best) or round_ == _PROOF_ROUNDS - 1 or out_of_time():
            break  # (in the last round the bounds, over the limits, make the mass proven lower)
        best, poses = candidate, proven.poses
    return _proven_mass(family, ranges, L, G0, best, proven, limited, (own_mass, load))


def _lighter(candidate: MaxPayload, best: MaxPayload) -> bool:
    return candidate.mass < best.mass * (1 - 1e-12) or math.isnan(candidate.mass)


def _most_loaded(family, ranges, dG):
    n = family.empty.n
    return ranges.maximize(lambda Q: family.static_torques(Q)[1], np.vstack([np.eye(n), -np.eye(n)]), dG)


def _proven_mass(family, ranges, L, G0, best: MaxPayload, at_best: Extremes, limited, known) -> MaxPayload:
    """``best`` if the bounds at its mass (capped at MAX_MASS) keep every joint within its
    limit, else the largest mass they prove: between two masses m0 < m1 the torques mix,
    (1 - s) tau(m0) + s tau(m1), and so do their bounds. m0: the payload's own mass if its
    bounds (``known``: (mass, Extremes)) are within the limits and below m1, else 0."""
    limit = np.tile(L, 2) * (1 + RTOL)
    m1, b = min(best.mass, MAX_MASS), at_best.bounds
    if np.all(b <= limit):
        return best
    m0, a = known[0], known[1].bounds
    if not (m0 < m1 and np.all(a[limited] <= limit[limited])):
        m0, a = 0.0, family.extremes(0.0, ranges, G0, rows=limited, share=MASS_PROOF_SHARE).bounds
    over_a, over_b = a > limit, b > limit
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # in joints np.where leaves out
        highest = np.min(np.where(over_b, (limit - a) / (b - a), 1.0))
        lowest = np.max(np.where(over_a, (a - limit) / (a - b), 0.0))
    proven = m0 + (m1 - m0) * highest if not (over_a & over_b).any() and lowest <= highest else math.nan
    with np.errstate(invalid="ignore"):
        worst = int(np.argmax(np.where(np.isfinite(limit), b - limit, -np.inf)))
    joint = best.joint if best.joint is not None else worst % len(L)
    q = best.q if best.q is not None else at_best.poses[worst]
    return _max_payload(proven, joint, q, gap=best.mass - (0.0 if math.isnan(proven) else proven))


def checked_payload_arguments(model, payload, rated_payload, q, qd):
    """The arguments of check_payload, checked (ModelError or ValueError naming them)."""
    if not isinstance(model, RobotModel):
        raise ModelError("model", f"expected a RobotModel, got {model!r}")
    payload, rated_payload = checked_body("payload", payload), checked_body("rated_payload", rated_payload)
    if q is None:
        return payload, rated_payload, None, None
    q = np.array(state(q, model.n, "q"), dtype=float)
    qd = np.zeros(model.n) if qd is None else np.array(state(qd, model.n, "qd"), dtype=float)
    return payload, rated_payload, q, qd
