"""The payload check: a payload against the joint torque limits, now and over the workspace,
with its figures and report (the same strings for ~/check and /diagnostics).

Units: kg, m, rad (poses shown in degrees), N m. A verdict is proven or says it is not:

- OK: every joint's torque now and the proven bound of its worst static torque are within
  its limit (a derived limit: the lowest it may be, see ``TorqueLimits.highest``);
- OVER-LIMIT: a real torque, now or in a pose the search found, is over the highest the
  joint's limit may be;
- UNPROVEN: neither, where a proof's budget or the analysis' time ran out with the true
  worst torque somewhere between the torque found and its bound, across the limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.model.rigid_body import RigidBody
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.payload.limits import (
    RATED_PAYLOAD,
    RTOL,
    MaxPayload,
    TorqueLimits,
    WorkspaceLoad,
    checked_payload_arguments,
    derive_torque_limits,
    limit_values,
    loads,
    max_payload_here,
    workspace_load,
)
from irb140_dynamics.core.payload.path import payload_path
from irb140_dynamics.core.payload.proof.harmonic import MAX_JOINTS

VISIBLE = 5e-4  # N m or kg: a gap the report's 3 decimals would show is worth a note


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
    sliding: tuple[bool, ...] = ()  # per joint: prismatic (its position shown in m, not degrees)

    @property
    def limit(self) -> np.ndarray:
        return np.asarray(self.limits.values)

    @property
    def use(self) -> np.ndarray | None:
        """|torque| / limit in percent (0 where there is no limit)."""
        return None if self.torque is None else _percent_of(np.abs(self.torque), self.limit)

    @property
    def worst_use(self) -> np.ndarray:
        """The proven bound of the worst static torque / limit in percent."""
        return _percent_of(self.workspace.bound, self.limit)

    @property
    def within(self) -> np.ndarray:
        """Per joint: proven within its limit, now (if a state is given) and in every pose."""
        ok = self.workspace.bound <= self.limit * (1 + RTOL)
        if self.torque is not None:
            ok &= np.abs(self.torque) <= self.limit * (1 + RTOL)
        return ok

    @property
    def beyond(self) -> np.ndarray:
        """Per joint: proven over its limit, by a real torque (now, or at a pose found)."""
        highest = self.limits.highest * (1 + RTOL)
        over = np.abs(self.workspace.torque) > highest
        if self.torque is not None:
            over |= np.abs(self.torque) > highest
        return over

    @property
    def verdict(self) -> str:
        """ "OVER-LIMIT", "OK" or "UNPROVEN" (see the module)."""
        return "OVER-LIMIT" if self.beyond.any() else "OK" if self.within.all() else "UNPROVEN"

    @property
    def ok(self) -> bool:
        return self.verdict == "OK"

    @property
    def over(self) -> list[str]:
        """The names of the joints proven over their limit."""
        return [name for name, over in zip(self.joint_names, self.beyond) if over]

    @property
    def unproven(self) -> list[str]:
        """The names of the joints neither proven within nor over their limit."""
        return [self.joint_names[j] for j in np.flatnonzero(~self.within & ~self.beyond)]

    def unfinished(self, j: int) -> str:
        """Why the proof left a gap at joint j, in words."""
        if self.workspace.out_of_time or self.limits.out_of_time:
            return "the analysis ran out of time"
        rest = float(np.broadcast_to(self.workspace.rest, self.workspace.bound.shape)[j])
        if rest > 0 and self.workspace.gap[j] <= rest * (1 + RTOL) + VISIBLE:
            return "the rest of the tree's worst pose is bounded, not found"
        if len(self.joint_names) > MAX_JOINTS:
            return f"the proof's budget ran out (plain interval bounds: more than {MAX_JOINTS} joints)"
        return "the proof's budget ran out"

    def headline(self) -> str:
        """The verdict in one line: OK, OVER-LIMIT or UNPROVEN, with the joint that decides it."""
        mass = f"{self.payload.mass:.3f} kg"
        verdict = self.verdict
        if verdict == "OK":
            return f"OK: {mass} fits, {self._most_used()}"
        if verdict == "OVER-LIMIT":
            return f"OVER-LIMIT: {mass} does not fit: {self._worst_over()}"
        return f"UNPROVEN: {mass} not proven to fit: {self._most_unproven()}"

    def _most_used(self) -> str:
        """The joint nearest its limit (proven use), in words."""
        use = np.fmax(self.worst_use, -np.inf if self.use is None else self.use)
        use = np.where(np.isfinite(self.limit) & (self.limit > 0), use, -np.inf)  # (a limit 0 held: nothing used)
        if not np.isfinite(use).any():
            return "no joint it loads has a limit"
        j = int(np.argmax(use))
        return f"worst {self.joint_names[j]} at {use[j]:.1f} % of its limit"

    def _worst_over(self) -> str:
        """The joint most over its limit, where, and the others over, in words."""
        highest = self.limits.highest
        now = np.zeros_like(highest) if self.torque is None else np.abs(self.torque)
        worst = np.maximum(now, np.abs(self.workspace.torque))
        j = int(np.argmax(np.where(self.beyond, worst / np.where(highest > 0, highest, 1e-300), -np.inf)))
        pose = _degrees(self.workspace.pose[j], self.sliding)
        where = "now" if now[j] >= abs(self.workspace.torque[j]) else f"at {pose} deg"
        text = (
            f"{self.joint_names[j]} needs {worst[j]:.3f} N m {where}, {_of_limit(worst[j], self.limit[j], highest[j])}"
        )
        others = [name for name in self.over if name != self.joint_names[j]]
        return text + (f"; also over: {', '.join(others)}" if others else "")

    def _most_unproven(self) -> str:
        """The unproven joint whose bound is furthest over its limit (of those whose limit
        is > 0, if any), the reason, and the others unproven, in words."""
        unproven = ~self.within & ~self.beyond
        if (unproven & (self.limit > 0)).any():
            unproven &= self.limit > 0
        j = int(np.argmax(np.where(unproven, self.worst_use, -np.inf)))
        name, load, limit, highest = self.joint_names[j], self.workspace, self.limit[j], self.limits.highest[j]
        found = abs(load.torque[j])
        if self.torque is not None and abs(self.torque[j]) > limit * (1 + RTOL):  # between the ends of its limit
            text = f"{name} needs {abs(self.torque[j]):.3f} N m now, {_of_limit(abs(self.torque[j]), limit, highest)}"
        else:
            share = f" ({100 * found / limit:.1f} %)" if 0 < limit < math.inf else ""
            text = (
                f"{name}'s worst static torque is proven only up to {load.bound[j]:.3f} N m, "
                f"{_of_limit(load.bound[j], limit, highest)}; found {found:.3f} N m{share}"
            )
        others = len(self.unproven) - 1
        more = f"; {others} more joint{'s' * (others > 1)} unproven" if others else ""
        return f"{text}: {self.unfinished(j)}{more}"

    @property
    def loaded_without_limit(self) -> list[int]:
        """The joints that have no limit and yet this payload loads (statically): their
        limit rule did not see this load, so nothing checks it."""
        return [int(j) for j in np.flatnonzero(np.isinf(self.limit) & loads(self.workspace.bound))]

    @property
    def open_gaps(self) -> list[int]:
        """The joints whose worst static torque the proof left visibly open (its budget ran out)."""
        return [int(j) for j in np.flatnonzero(self.workspace.gap >= VISIBLE)]

    def no_limit_note(self, j: int) -> str:
        """Why joint j (of loaded_without_limit) wants a given torque limit."""
        name = self.joint_names[j]
        return (
            f"{name} has no limit, yet this payload loads it ({self.workspace.torque[j]:.3f} N m "
            f"in its worst pose): set {name}.torque_limit"
        )

    def gap_note(self, j: int) -> str:
        """What the proof left open at joint j (of open_gaps)."""
        load = self.workspace
        return (
            f"{self.joint_names[j]}: worst static torque proven only up to {load.bound[j]:.3f} N m "
            f"(gap {load.gap[j]:.3g} N m: {self.unfinished(j)})"
        )

    # -- the figures, formatted once for the report and /diagnostics --------------------

    def joint_figures(self, j: int) -> dict[str, str]:
        """Joint j's figures by label, in the order of the report's columns (on a tree whose
        rest loads the path, the rest of the tree in the worst pose last)."""
        L, load, now = self.limit[j], self.workspace, self.torque is not None
        worst_use = _percent(self.worst_use[j], L)  # of the bound: "<=" where it is not the torque found
        if load.gap[j] >= VISIBLE and worst_use != "-":
            worst_use = "<=" + worst_use
        return {
            "torque now [N m]": f"{self.torque[j]:.3f}" if now else "-",
            "limit [N m]": "none" if math.inf == L else f"{L:.3f}",
            "use now": _percent(self.use[j], L) if now else "-",
            "worst static torque [N m]": f"{load.torque[j]:.3f}",
            "worst use": worst_use,
            "worst pose [deg]": _degrees(load.pose[j], self.sliding),
            "limit source": self.limits.reason(j),
            "worst static bound [N m]": f"{load.bound[j]:.3f}",
            "worst static gap [N m]": f"{load.gap[j]:.2g}",
        } | ({"rest of the tree in the worst pose [deg]": load.rest_pose[j] or "-"} if load.rest_pose else {})

    def joint_status(self, j: int, warn_use: float) -> tuple[str, str]:
        """Joint j's level ('OK'; 'WARN' from ``warn_use`` %, when the payload loads it
        without a limit, or when the proof cannot tell whether it is within its limit;
        'ERROR' proven over it) and its message in one line."""
        figures, finite = self.joint_figures(j), math.isfinite(self.limit[j])
        uses = {"worst use": self.worst_use[j], **({} if self.use is None else {"use now": self.use[j]})}
        most = max(uses, key=uses.get)
        of_limit = f"{figures[most]} of its {figures['limit [N m]']} N m limit"
        if self.beyond[j]:
            return "ERROR", of_limit if finite else figures["limit source"]
        if not self.within[j]:
            return "WARN", f"unproven: {of_limit} by its bound: {self.unfinished(j)}"
        if finite:
            return ("WARN" if uses[most] >= warn_use else "OK"), of_limit
        if j in self.loaded_without_limit:
            return "WARN", self.no_limit_note(j)
        return "OK", figures["limit source"]

    def payload_figures(self) -> dict[str, str]:
        """The payload and its largest masses by label ("here" only with a state)."""
        figures = {"payload mass [kg]": f"{self.payload.mass:.3f}", "payload com [m]": _vector(self.payload.com)}
        for where, best in (("here", self.max_payload_here), ("over the workspace", self.workspace.max_payload)):
            if best is not None:
                mass, joint, pose = _max_payload_figures(best, self.joint_names, self.limits, self.sliding)
                label = f"max payload {where}"
                figures.update({f"{label} [kg]": mass, f"{label}: limited by": joint, f"{label}: pose [deg]": pose})
        figures["max payload over the workspace: gap [kg]"] = f"{self.workspace.max_payload.gap:.2g}"
        figures["worst static torques: gap [N m]"] = f"{max(self.workspace.gap.max(), 0.0):.2g}"
        return figures

    def report(self) -> str:
        """The check as short text: the verdict in one line (``headline``), then the payload,
        one line per joint, the largest payloads, then notes."""
        payload = self.payload_figures()
        header = ["joint", "now [N m]", "limit [N m]", "use", "worst [N m]", "use"]
        rows = [[name, *list(self.joint_figures(j).values())[:6]] for j, name in enumerate(self.joint_names)]
        lines = [self.headline(), f"payload {payload['payload mass [kg]']} kg at {payload['payload com [m]']} m"]
        lines += _table(header + ["worst pose [deg]"], rows, widths=(10, 11, 13, 8, 13, 8))
        lines += [f"the rest of the tree in {name}'s worst pose [deg]: {rest}" for name, rest in
                  zip(self.joint_names, self.workspace.rest_pose) if rest]  # fmt: skip
        lines.append("limits: " + self._limits_note())
        here = "" if self.max_payload_here is None else f"{_max_payload_text(payload, 'here')} here, "
        lines.append(f"max payload: {here}{_max_payload_text(payload, 'over the workspace')} over the workspace")
        lines.append(f"proof: the worst static torques are exact to {payload['worst static torques: gap [N m]']} N m")
        lines += [f"note: {self.gap_note(j)}" for j in self.open_gaps]
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
    ranges (``workspace``: a cached workspace_load(model, payload, limits) may be passed).
    On a tree: the joints up to the payload's link (model.carrier), with the rest of the
    tree in its worst pose (see ``path``); q and qd are the tree's."""
    payload, rated_payload, q, qd = checked_payload_arguments(model, payload, rated_payload, q, qd)
    if limits is None:
        limits = derive_torque_limits(model, rated_payload)
    elif not isinstance(limits, TorqueLimits):
        raise ValueError(f"limits: expected TorqueLimits (see derive_torque_limits), got {limits!r}")
    path = payload_path(model)  # on a tree: the joints up to the payload's link, the rest in its worst pose
    L = limit_values(limits, path.chain.n)
    if workspace is None:
        workspace = workspace_load(model, payload, limits)
    names, sliding = path.chain.joint_names, tuple(joint.prismatic for joint in path.chain.joints)
    if q is None:
        return PayloadCheck(names, payload, limits, workspace, sliding=sliding)
    tau0, dtau = path.torques(payload, q, qd)
    q, qd = q[path.columns], qd[path.columns]
    here = max_payload_here(tau0, dtau, L, q)
    torque = tau0 + payload.mass * dtau
    return PayloadCheck(names, payload, limits, workspace, q, qd, torque, here, sliding)


# -- text ------------------------------------------------------------------------------------------


def _table(header: list[str], rows: list[list[str]], widths) -> list[str]:
    """Rows of text columns: the first left-aligned, the last (free) after two spaces, the
    others right-aligned in at least ``widths`` characters and always two spaces apart."""
    columns = list(zip(header, *rows))[1:-1]
    fit = [max(w, 2 + max(len(x) for x in column)) for w, column in zip(widths[1:], columns)]
    first = max(widths[0], 2 + max(len(row[0]) for row in [header] + rows))

    def line(cells):
        return f"{cells[0]:<{first}}" + "".join(f"{x:>{w}}" for x, w in zip(cells[1:-1], fit)) + f"  {cells[-1]}"

    return [line(header)] + [line(row) for row in rows]


def _vector(x) -> str:
    return "(" + ", ".join(f"{v:.3f}" for v in x) + ")"


def _degrees(q, sliding=()) -> str:
    """A pose in degrees, a prismatic joint's position in m: "(0, 45.2, 0.250 m)"."""
    shown = [
        f"{x:.3f} m" if k < len(sliding) and sliding[k] else f"{round(math.degrees(x), 1) + 0.0:g}"
        for k, x in enumerate(q)
    ]
    return "(" + ", ".join(shown) + ")"


def _percent_of(torque, limit):
    """torque / limit in percent (inf over a limit 0, nan for 0 of 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return 100 * np.asarray(torque, dtype=float) / limit


def _of_limit(torque: float, limit: float, highest: float) -> str:
    """A torque against its limit in words: "110.2 % of its 6.256 N m limit"."""
    share = f"{100 * torque / limit:.1f} % of " if 0 < limit < math.inf else "against "
    return share + _limit_text(limit, highest)


def _limit_text(limit: float, highest: float) -> str:
    """A limit in words: "its 290.765 N m limit", and how high a derived one may be where
    the proof of the rated payload's worst torque left a gap."""
    if highest > limit * (1 + RTOL):
        return f"its {limit:.3f} N m limit (derived: it may be up to {highest:.3f} N m)"
    return f"its {limit:.3f} N m limit"


def _percent(use: float, L: float) -> str:
    return "-" if math.inf == L else f"{use:.1f}%"


def _max_payload_figures(best: MaxPayload, names, limits: TorqueLimits, sliding=()) -> tuple[str, str, str]:
    """(mass [kg]: a number, "none", "none proven" (over a derived limit the proof left
    open) or "unbounded"; the joint at or over its limit; the pose [deg]), "-" where there
    is none."""
    if best.mass == math.inf:
        return "unbounded", "-", "-"
    certain = limits.highest[best.joint] <= limits.values[best.joint] * (1 + RTOL)
    mass = ("none" if certain else "none proven") if math.isnan(best.mass) else f"{best.mass:.3f}"
    return mass, names[best.joint], _degrees(best.q, sliding)


def _max_payload_text(figures: dict[str, str], where: str) -> str:
    """A largest payload of payload_figures in words: "6.000 kg (joint_2)", with the pose
    over the workspace, and what the proof left open."""
    label = f"max payload {where}"
    mass, joint, pose = (figures[f"{label}{key}"] for key in (" [kg]", ": limited by", ": pose [deg]"))
    gap = float(figures.get(f"{label}: gap [kg]", "0"))
    at = f" at {pose} deg" if where != "here" else ""
    if mass == "unbounded":
        return mass
    if mass == "none proven":
        return f"none proven ({joint}{at}: its derived limit is known only up to a gap)"
    if mass == "none" and gap > 0:
        return f"none proven ({joint}{at}; the search found {gap:.3f} kg, the proof's budget ran out)"
    if mass == "none":
        return f"none ({joint} over its limit)"
    more = f"; perhaps {gap:.3f} kg more: the proof's budget ran out" if gap >= VISIBLE else ""
    return f"{mass} kg ({joint}{at}{more})"
