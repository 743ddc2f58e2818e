"""Payload analysis: joint torque limits from the rated payload, the worst static load of a
payload over the joint ranges, and the largest payload a pose or the whole workspace holds.

Units: kg, m, rad, N m. A payload is a RigidBody on the flange (frame n); it replaces the
model's own payload. For a fixed CoM and inertia the torques are affine in the payload
mass m,

    tau(m) = tau0 + m dtau,

so the largest payload is exact, no trial and error: at one state each joint allows an
interval of masses (|tau_j(m)| <= L_j); over the workspace Dinkelbach's iteration finds it
(the worst poses at mass m allow a mass <= m; repeat at that mass until it stops falling).

The permissible torques follow the report (section 10): the torques of the rated payload,
6 kg at the flange origin, in the pose that loads each joint most. A given torque limit
(``Joint.torque_limit`` > 0) always overrides.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Sequence

import numpy as np

from .dynamics import gravity_batch, rnea
from .model import RobotModel
from .rigid_body import RigidBody
from .workspace import JointRanges

RATED_PAYLOAD = RigidBody(6.0)  # the IRB-140's rated payload: 6 kg at the flange origin
RTOL = 1e-9  # a torque within RTOL of its limit is within it


# -- torques affine in the payload mass -------------------------------------------------------


@dataclass(frozen=True)
class PayloadFamily:
    """The model carrying one payload (CoM, inertia) at any mass m: tau(m) = tau0 + m dtau."""

    empty: RobotModel  # the payload at 0 kg
    unit: RobotModel  # the payload at 1 kg

    def torques(self, q, qd) -> tuple[np.ndarray, np.ndarray]:
        """(tau0, dtau) [N m, N m/kg] that hold the motion (q, qd) with qdd = 0."""
        qdd = np.zeros(len(q))
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


def payload_family(model: RobotModel, payload: RigidBody) -> PayloadFamily:
    """``payload``'s shape at any mass on ``model`` (whatever payload ``model`` carries).

    Built once per arm and shape: the two models validate the CoM and inertia (ModelError
    naming ``payload.com`` or ``payload.inertia``) and compile their kernels then.
    """
    return _family(model.joints, model.gravity, tuple(payload.com), tuple(payload.inertia))


@lru_cache(maxsize=16)
def _family(joints, gravity, com, inertia) -> PayloadFamily:
    def carrying(mass):
        return RobotModel(joints, gravity, RigidBody(mass, com, inertia))

    return PayloadFamily(carrying(0.0), carrying(1.0))


def mass_bounds(tau0, dtau, limits) -> tuple[np.ndarray, np.ndarray]:
    """Per joint, the payload masses m with |tau0 + m dtau| <= L: (lower, upper) [kg].

    Works on (..., n) arrays; L = inf is no limit. An empty interval has lower > upper.
    A dtau_j below 1e-12 of the largest is rounding noise: the payload does not load joint j.
    """
    tau0, dtau, L = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (tau0, dtau, limits)))
    dtau = np.where(np.abs(dtau) <= 1e-12 * np.max(np.abs(dtau), axis=-1, keepdims=True), 0.0, dtau)
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
    joint = np.argmax(_at_most(upper, m[..., None]), axis=-1)
    fits = np.maximum(0.0, np.max(lower, axis=-1)) <= m
    return np.where(fits, m, np.nan), joint


def loads(torque) -> np.ndarray:
    """Per joint: is the (worst) static torque more than rounding noise, i.e. does the load
    reach the joint at all? Noise: RTOL of the largest, or of 1 N m."""
    worst = np.abs(torque)
    return worst > RTOL * max(worst.max(), 1.0)


def _at_most(x, m):
    """x <= m, a value within RTOL of m counting as equal to it."""
    with np.errstate(invalid="ignore"):
        return (x <= m) | (x <= m + RTOL * np.abs(m))


# -- results ------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class MaxPayload:
    """The largest payload mass [kg] (nan: none fits; inf: unbounded), the joint at its
    limit there (index; None if unbounded) and the pose q [rad] where that happens."""

    mass: float
    joint: int | None
    q: np.ndarray | None


def _max_payload(m: float, joint: int, q) -> MaxPayload:
    if m == math.inf:
        return MaxPayload(m, None, None)
    return MaxPayload(m, joint, np.asarray(q, dtype=float))


@dataclass(frozen=True, eq=False)
class TorqueLimits:
    """Joint torque limits [N m] (inf: none), where each comes from, and the rated payload's
    worst static torque per joint with its pose (row j for joint j)."""

    values: tuple[float, ...]
    source: tuple[str, ...]  # "given", "derived" or "none"
    rated_payload: RigidBody
    rated_torque: np.ndarray  # (n,) N m, signed
    rated_pose: np.ndarray  # (n, n) rad

    def reason(self, j: int) -> str:
        """Why joint j has its limit, in words."""
        rated = self.rated_payload
        return {
            "given": "given (torque_limit)",
            "derived": f"worst static torque of the rated payload, "
            f"{rated.mass:.3f} kg at {_vector(rated.com)} m",
            "none": "none: the rated payload cannot load it",
        }[self.source[j]]


@dataclass(frozen=True, eq=False)
class WorkspaceLoad:
    """A payload's worst static torque per joint over the joint ranges and its pose (row j
    for joint j), and the largest payload of its shape that every pose holds."""

    payload: RigidBody
    torque: np.ndarray  # (n,) N m, signed
    pose: np.ndarray  # (n, n) rad
    max_payload: MaxPayload


# -- worst static torques and the limits derived from them ---------------------------------------


def static_extremes(torque, ranges: JointRanges, sample_torques=None, warm=None):
    """max tau_j and max -tau_j over the joint ranges of static torques Q -> tau:
    (values (2n,), poses (2n, n)), rows j and n + j for joint j."""
    n = ranges.lower.size
    return ranges.maximize(torque, np.vstack([np.eye(n), -np.eye(n)]), sample_torques, warm)


def _largest(values: np.ndarray, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per joint the signed torque of largest magnitude and its pose, from static_extremes."""
    n = values.size // 2
    positive = values[:n] >= values[n:] - RTOL * np.max(np.abs(values))  # a tie goes to +tau_j
    torque = np.where(positive, values[:n], -values[n:])
    return torque, np.where(positive[:, None], poses[:n], poses[n:])


def derive_torque_limits(model: RobotModel, rated_payload: RigidBody = RATED_PAYLOAD) -> TorqueLimits:
    """Each joint's limit: its given torque_limit if > 0, else the worst static torque of
    the rated payload over the joint ranges; none (inf) for a joint it cannot load."""
    rated = payload_family(model, rated_payload).static_torque(rated_payload.mass)
    torque, pose = _largest(*static_extremes(rated, JointRanges.of(model)))
    loaded = loads(torque)
    given = np.array(model.torque_limits) > 0
    source = np.where(given, "given", np.where(loaded, "derived", "none"))
    limits = np.where(given, model.torque_limits, np.where(loaded, np.abs(torque), np.inf))
    return TorqueLimits(tuple(limits.tolist()), tuple(source.tolist()), rated_payload, torque, pose)


def _limit_values(limits: TorqueLimits | Sequence[float]) -> np.ndarray:
    return np.asarray(limits.values if isinstance(limits, TorqueLimits) else limits, dtype=float)


# -- the largest payload -------------------------------------------------------------------------


def max_payload_at(model: RobotModel, payload: RigidBody, limits, q, qd=None) -> MaxPayload:
    """The largest mass of ``payload``'s shape that the state (q, qd), qdd = 0, can hold."""
    tau0, dtau = payload_family(model, payload).torques(q, np.zeros(model.n) if qd is None else qd)
    return _max_payload_here(tau0, dtau, limits, q)


def _max_payload_here(tau0, dtau, limits, q) -> MaxPayload:
    m, joint = max_mass(tau0, dtau, _limit_values(limits))
    return _max_payload(float(m), int(joint), q)


def _smallest_max_payload(family: PayloadFamily, poses: np.ndarray, L: np.ndarray) -> MaxPayload:
    """The least of the largest static payloads of poses (N, n) (nan if one holds none);
    of tied poses the one whose limiting joint comes first."""
    m, joint = max_mass(*family.static_torques(poses), L)
    if np.isnan(m).any():
        i = int(np.argmax(np.isnan(m)))
    else:
        i = int(np.argmin(np.where(_at_most(m, m.min()), joint, joint.size + m.size)))
    return _max_payload(float(m[i]), int(joint[i]), poses[i])


def workspace_load(
    model: RobotModel,
    payload: RigidBody,
    limits: TorqueLimits | Sequence[float],
    ranges: JointRanges | None = None,
) -> WorkspaceLoad:
    """The payload's worst static torques over the joint ranges, and the largest payload of
    its shape that holds still within the limits in every pose. Depends only on its
    arguments: cache it."""
    L = _limit_values(limits)
    ranges = JointRanges.of(model) if ranges is None else ranges
    family = payload_family(model, payload)
    G0, dG = family.static_torques(ranges.samples)

    def extremes(m, warm=None):
        return static_extremes(family.static_torque(m), ranges, G0 + m * dG, warm)

    values, poses = extremes(payload.mass)
    torque, pose = _largest(values, poses)
    best = _smallest_max_payload(family, poses, L)
    if best.mass == math.inf:  # no limited joint loaded there: try where the payload loads them most
        _, poses = static_extremes(lambda Q: family.static_torques(Q)[1], ranges, dG)
        best = _smallest_max_payload(family, poses, L)
    while math.isfinite(best.mass):  # Dinkelbach
        _, poses = extremes(best.mass, warm=poses)
        candidate = _smallest_max_payload(family, poses, L)
        if not (candidate.mass < best.mass * (1 - 1e-12) or math.isnan(candidate.mass)):
            break
        best = candidate
    return WorkspaceLoad(payload, torque, pose, best)


# -- the check -----------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class PayloadCheck:
    """A payload against the joint torque limits: at the state (q, qd) with qdd = 0 (if
    given) and in each joint's worst static pose over the joint ranges."""

    joint_names: tuple[str, ...]
    payload: RigidBody
    limits: TorqueLimits
    workspace: WorkspaceLoad
    q: np.ndarray | None = None
    qd: np.ndarray | None = None
    torque: np.ndarray | None = None  # (n,) N m needed at (q, qd)
    max_payload_here: MaxPayload | None = None

    @property
    def limit(self) -> np.ndarray:
        return np.asarray(self.limits.values)

    @property
    def use(self) -> np.ndarray | None:
        """|torque| / limit in percent (0 where there is no limit)."""
        return None if self.torque is None else 100 * np.abs(self.torque) / self.limit

    @property
    def worst_use(self) -> np.ndarray:
        return 100 * np.abs(self.workspace.torque) / self.limit

    @property
    def within(self) -> np.ndarray:
        """Per joint: within its limit now (if a state is given) and in its worst pose."""
        ok = np.abs(self.workspace.torque) <= self.limit * (1 + RTOL)
        if self.torque is not None:
            ok &= np.abs(self.torque) <= self.limit * (1 + RTOL)
        return ok

    @property
    def ok(self) -> bool:
        return bool(self.within.all())

    @property
    def over(self) -> list[str]:
        """The names of the joints over their limit."""
        return [name for name, ok in zip(self.joint_names, self.within) if not ok]

    @property
    def loaded_without_limit(self) -> list[int]:
        """The joints that have no limit and yet this payload loads (statically): their
        limit rule did not see this load, so nothing checks it."""
        return [int(j) for j in np.flatnonzero(np.isinf(self.limit) & loads(self.workspace.torque))]

    def no_limit_note(self, j: int) -> str:
        """Why joint j (of loaded_without_limit) wants a given torque limit."""
        name = self.joint_names[j]
        return (f"{name} has no limit, yet this payload loads it ({self.workspace.torque[j]:.3f} N m "
                f"in its worst pose): set {name}.torque_limit")

    # -- the figures, formatted once for the report and /diagnostics --------------------

    def joint_figures(self, j: int) -> dict[str, str]:
        """Joint j's figures by label, in the order of the report's columns."""
        L, load, now = self.limit[j], self.workspace, self.torque is not None
        return {
            "torque now [N m]": f"{self.torque[j]:.3f}" if now else "-",
            "limit [N m]": "none" if L == math.inf else f"{L:.3f}",
            "use now": _percent(self.use[j], L) if now else "-",
            "worst static torque [N m]": f"{load.torque[j]:.3f}",
            "worst use": _percent(self.worst_use[j], L),
            "worst pose [deg]": _degrees(load.pose[j]),
            "limit source": self.limits.reason(j),
        }

    def payload_figures(self) -> dict[str, str]:
        """The payload and its largest masses by label ("here" only with a state)."""
        figures = {"payload mass [kg]": f"{self.payload.mass:.3f}", "payload com [m]": _vector(self.payload.com)}
        for where, best in (("here", self.max_payload_here), ("over the workspace", self.workspace.max_payload)):
            if best is not None:
                mass, joint, pose = _max_payload_figures(best, self.joint_names)
                label = f"max payload {where}"
                figures.update({f"{label} [kg]": mass, f"{label}: limited by": joint, f"{label}: pose [deg]": pose})
        return figures

    def report(self) -> str:
        """The check as short text: one line per joint, the largest payloads, then notes."""
        status = "OVER THE LIMIT at " + ", ".join(self.over) if self.over else "OK"
        payload = self.payload_figures()
        lines = [
            f"payload {payload['payload mass [kg]']} kg at {payload['payload com [m]']} m: {status}",
            f"{'joint':<10}{'now [N m]':>11}{'limit [N m]':>13}{'use':>8}"
            f"{'worst [N m]':>13}{'use':>8}  worst pose [deg]",
        ]
        for j, name in enumerate(self.joint_names):
            now, limit, use, worst, worst_use, pose, _ = self.joint_figures(j).values()
            lines.append(f"{name:<10}{now:>11}{limit:>13}{use:>8}{worst:>13}{worst_use:>8}  {pose}")
        lines.append("limits: " + self._limits_note())
        here = "" if self.max_payload_here is None else f"{_max_payload_text(payload, 'here')} here, "
        lines.append(f"max payload: {here}{_max_payload_text(payload, 'over the workspace')} over the workspace")
        lines += [f"note: {self.no_limit_note(j)}" for j in self.loaded_without_limit]
        return "\n".join(lines)

    def _limits_note(self) -> str:
        """The joints grouped by the reason of their limit."""
        groups: dict[str, list[int]] = {}
        for j, source in enumerate(self.limits.source):
            groups.setdefault(source, []).append(j)
        return "; ".join(
            f"{', '.join(self.joint_names[j] for j in joints)}: {self.limits.reason(joints[0])}"
            for joints in groups.values()
        )


def check_payload(
    model: RobotModel,
    payload: RigidBody,
    limits: TorqueLimits | None = None,
    q=None,
    qd=None,
    rated_payload: RigidBody = RATED_PAYLOAD,
    workspace: WorkspaceLoad | None = None,
) -> PayloadCheck:
    """Check ``payload`` against the torque limits (default: derive_torque_limits(model,
    rated_payload)) at the state (q, qd) with qdd = 0, if q is given, and over the joint
    ranges (``workspace``: a cached workspace_load(model, payload, limits) may be passed)."""
    if limits is None:
        limits = derive_torque_limits(model, rated_payload)
    if workspace is None:
        workspace = workspace_load(model, payload, limits)
    if q is None:
        return PayloadCheck(model.joint_names, payload, limits, workspace)
    q = np.asarray(q, dtype=float)
    qd = np.zeros(model.n) if qd is None else np.asarray(qd, dtype=float)
    tau0, dtau = payload_family(model, payload).torques(q, qd)
    here = _max_payload_here(tau0, dtau, limits, q)
    torque = tau0 + payload.mass * dtau
    return PayloadCheck(model.joint_names, payload, limits, workspace, q, qd, torque, here)


# -- text ------------------------------------------------------------------------------------------


def _vector(x) -> str:
    return "(" + ", ".join(f"{v:.3f}" for v in x) + ")"


def _degrees(q) -> str:
    return "(" + ", ".join(f"{round(v, 1) + 0.0:g}" for v in np.degrees(q)) + ")"


def _percent(use: float, L: float) -> str:
    return "-" if L == math.inf else f"{use:.1f}%"


def _max_payload_figures(best: MaxPayload, names) -> tuple[str, str, str]:
    """(mass [kg]: a number, "none" or "unbounded"; the joint at or over its limit; the
    pose [deg]), "-" where there is none."""
    if best.mass == math.inf:
        return "unbounded", "-", "-"
    mass = "none" if math.isnan(best.mass) else f"{best.mass:.3f}"
    return mass, names[best.joint], _degrees(best.q)


def _max_payload_text(figures: dict[str, str], where: str) -> str:
    """A largest payload of payload_figures in words: "6.000 kg (joint_2)", with the pose
    over the workspace."""
    label = f"max payload {where}"
    mass, joint, pose = (figures[f"{label}{key}"] for key in (" [kg]", ": limited by", ": pose [deg]"))
    if mass == "unbounded":
        return mass
    if mass == "none":
        return f"none ({joint} over its limit)"
    at = f" at {pose} deg" if where != "here" else ""
    return f"{mass} kg ({joint}{at})"
