"""The payload check: a payload against the joint torque limits, now and over the workspace,
with its figures and report (the same strings for ~/check and /diagnostics).

Units: kg, m, rad (poses shown in degrees), N m. The worst static torques count by their
proven bounds (see ``payload``): a joint is within its limit only if the bound is.
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
    payload_family,
    workspace_load,
)

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

    @property
    def limit(self) -> np.ndarray:
        return np.asarray(self.limits.values)

    @property
    def use(self) -> np.ndarray | None:
        """|torque| / limit in percent (0 where there is no limit)."""
        return None if self.torque is None else 100 * np.abs(self.torque) / self.limit

    @property
    def worst_use(self) -> np.ndarray:
        """The proven bound of the worst static torque / limit in percent."""
        return 100 * self.workspace.bound / self.limit

    @property
    def within(self) -> np.ndarray:
        """Per joint: within its limit now (if a state is given) and, proven, in every pose."""
        ok = self.workspace.bound <= self.limit * (1 + RTOL)
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
            f"(gap {load.gap[j]:.3g} N m, the proof's budget ran out): the check uses the bound"
        )

    # -- the figures, formatted once for the report and /diagnostics --------------------

    def joint_figures(self, j: int) -> dict[str, str]:
        """Joint j's figures by label, in the order of the report's columns."""
        L, load, now = self.limit[j], self.workspace, self.torque is not None
        return {
            "torque now [N m]": f"{self.torque[j]:.3f}" if now else "-",
            "limit [N m]": "none" if math.inf == L else f"{L:.3f}",
            "use now": _percent(self.use[j], L) if now else "-",
            "worst static torque [N m]": f"{load.torque[j]:.3f}",
            "worst use": _percent(self.worst_use[j], L),
            "worst pose [deg]": _degrees(load.pose[j]),
            "limit source": self.limits.reason(j),
            "worst static bound [N m]": f"{load.bound[j]:.3f}",
            "worst static gap [N m]": f"{load.gap[j]:.2g}",
        }

    def payload_figures(self) -> dict[str, str]:
        """The payload and its largest masses by label ("here" only with a state)."""
        figures = {"payload mass [kg]": f"{self.payload.mass:.3f}", "payload com [m]": _vector(self.payload.com)}
        for where, best in (("here", self.max_payload_here), ("over the workspace", self.workspace.max_payload)):
            if best is not None:
                mass, joint, pose = _max_payload_figures(best, self.joint_names)
                label = f"max payload {where}"
                figures.update({f"{label} [kg]": mass, f"{label}: limited by": joint, f"{label}: pose [deg]": pose})
        figures["max payload over the workspace: gap [kg]"] = f"{self.workspace.max_payload.gap:.2g}"
        figures["worst static torques: gap [N m]"] = f"{max(self.workspace.gap.max(), 0.0):.2g}"
        return figures

    def report(self) -> str:
        """The check as short text: one line per joint, the largest payloads, then notes."""
        status = "OVER THE LIMIT at " + ", ".join(self.over) if self.over else "OK"
        payload = self.payload_figures()
        header = ["joint", "now [N m]", "limit [N m]", "use", "worst [N m]", "use"]
        rows = [[name, *list(self.joint_figures(j).values())[:6]] for j, name in enumerate(self.joint_names)]
        lines = [f"payload {payload['payload mass [kg]']} kg at {payload['payload com [m]']} m: {status}"]
        lines += _table(header + ["worst pose [deg]"], rows, widths=(10, 11, 13, 8, 13, 8))
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
    ranges (``workspace``: a cached workspace_load(model, payload, limits) may be passed)."""
    payload, rated_payload, q, qd = checked_payload_arguments(model, payload, rated_payload, q, qd)
    if limits is None:
        limits = derive_torque_limits(model, rated_payload)
    elif not isinstance(limits, TorqueLimits):
        raise ValueError(f"limits: expected TorqueLimits (see derive_torque_limits), got {limits!r}")
    L = limit_values(limits, model.n)
    if workspace is None:
        workspace = workspace_load(model, payload, limits)
    if q is None:
        return PayloadCheck(model.joint_names, payload, limits, workspace)
    tau0, dtau = payload_family(model, payload).torques(q, qd)
    here = max_payload_here(tau0, dtau, L, q)
    torque = tau0 + payload.mass * dtau
    return PayloadCheck(model.joint_names, payload, limits, workspace, q, qd, torque, here)


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


def _degrees(q) -> str:
    return "(" + ", ".join(f"{round(v, 1) + 0.0:g}" for v in np.degrees(q)) + ")"


def _percent(use: float, L: float) -> str:
    return "-" if math.inf == L else f"{use:.1f}%"


def _max_payload_figures(best: MaxPayload, names) -> tuple[str, str, str]:
    """(mass [kg]: a number, "none" or "unbounded"; the joint at or over its limit; the
    pose [deg]), "-" where there is none."""
    if best.mass == math.inf:
        return "unbounded", "-", "-"
    mass = "none" if math.isnan(best.mass) else f"{best.mass:.3f}"
    return mass, names[best.joint], _degrees(best.q)


def _max_payload_text(figures: dict[str, str], where: str) -> str:
    """A largest payload of payload_figures in words: "6.000 kg (joint_2)", with the pose
    over the workspace, and what the proof left open."""
    label = f"max payload {where}"
    mass, joint, pose = (figures[f"{label}{key}"] for key in (" [kg]", ": limited by", ": pose [deg]"))
    gap = float(figures.get(f"{label}: gap [kg]", "0"))
    at = f" at {pose} deg" if where != "here" else ""
    if mass == "unbounded":
        return mass
    if mass == "none" and gap > 0:
        return f"none proven ({joint}{at}; the search found {gap:.3f} kg, the proof's budget ran out)"
    if mass == "none":
        return f"none ({joint} over its limit)"
    more = f"; perhaps {gap:.3f} kg more: the proof's budget ran out" if gap >= VISIBLE else ""
    return f"{mass} kg ({joint}{at}{more})"
