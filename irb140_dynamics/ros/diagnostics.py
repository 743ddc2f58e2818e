"""A payload check as diagnostic_msgs statuses, for rqt_robot_monitor and aggregators."""

from __future__ import annotations

import math

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue

from ..core.payload import MaxPayload, PayloadCheck

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


def payload_statuses(check: PayloadCheck, node_name: str, warn_use: float) -> list[DiagnosticStatus]:
    """One status per joint (OK / WARN from ``warn_use`` % / ERROR over its limit), then one
    for the payload with the largest payloads. Figures as in the check's report."""
    statuses = [_joint_status(check, j, node_name, warn_use) for j in range(len(check.joint_names))]
    level = max(status.level for status in statuses)
    names = check.joint_names
    over = [name for name, ok in zip(names, check.within) if not ok]
    summary = DiagnosticStatus(
        level=level,
        name=f"{node_name}: payload",
        hardware_id=node_name,
        message=f"{check.payload.mass:.3f} kg: " + ("OK" if not over else "over the limit at " + ", ".join(over)),
        values=[
            KeyValue(key="payload mass [kg]", value=f"{check.payload.mass:.3f}"),
            KeyValue(key="payload com [m]", value=_numbers(check.payload.com, 3)),
            *_max_payload_values("max payload here", check.max_payload_here, names),
            *_max_payload_values("max payload over the workspace", check.workspace.max_payload, names),
        ],
    )
    return statuses + [summary]


def _joint_status(check: PayloadCheck, j: int, node_name: str, warn_use: float) -> DiagnosticStatus:
    limit = check.limit[j]
    uses = [check.worst_use[j]] + ([] if check.use is None else [check.use[j]])
    if not check.within[j]:
        level = ERROR
    elif math.isfinite(limit) and max(uses) >= warn_use:
        level = WARN
    else:
        level = OK
    if math.isfinite(limit):
        message = f"{max(uses):.1f}% of its {limit:.3f} N m limit"
    else:
        message = f"no limit: {check.limits.reason(j)}"
    values = [
        KeyValue(key="limit [N m]", value="none" if not math.isfinite(limit) else f"{limit:.3f}"),
        KeyValue(key="limit source", value=check.limits.reason(j)),
        KeyValue(key="worst static torque [N m]", value=f"{check.workspace.torque[j]:.3f}"),
        KeyValue(key="worst use [%]", value=_percent(check.worst_use[j], limit)),
        KeyValue(key="worst pose [deg]", value=_numbers(np.degrees(check.workspace.pose[j]), 1)),
    ]
    if check.torque is not None:
        values += [
            KeyValue(key="torque now [N m]", value=f"{check.torque[j]:.3f}"),
            KeyValue(key="use now [%]", value=_percent(check.use[j], limit)),
        ]
    return DiagnosticStatus(
        level=level, name=f"{node_name}: {check.joint_names[j]}", hardware_id=node_name,
        message=message, values=values,
    )


def _max_payload_values(label: str, best: MaxPayload | None, names) -> list[KeyValue]:
    if best is None:
        return []
    if math.isnan(best.mass):
        mass = "none"
    elif math.isinf(best.mass):
        mass = "unbounded"
    else:
        mass = f"{best.mass:.3f}"
    values = [KeyValue(key=f"{label} [kg]", value=mass)]
    if best.joint is not None:
        values.append(KeyValue(key=f"{label}: limited by", value=names[best.joint]))
        values.append(KeyValue(key=f"{label}: pose [deg]", value=_numbers(np.degrees(best.q), 1)))
    return values


def _percent(use: float, limit: float) -> str:
    return f"{use:.1f}" if math.isfinite(limit) else "-"


def _numbers(values, digits: int) -> str:
    return "[" + ", ".join(f"{v + 0.0:.{digits}f}" for v in values) + "]"
