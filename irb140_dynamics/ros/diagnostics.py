"""A payload check as diagnostic_msgs statuses, for rqt_robot_monitor and aggregators.

The key-values are the check's own figures (PayloadCheck.joint_figures, payload_figures):
the same strings as in the ~/check report.
"""

from __future__ import annotations

import math

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue

from ..core.payload import PayloadCheck

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


def payload_statuses(
    check: PayloadCheck, node_name: str, warn_use: float, stale: str | None = None
) -> list[DiagnosticStatus]:
    """One status per joint (OK; WARN from ``warn_use`` % or when the payload loads a joint
    without a limit; ERROR over its limit), then one for the payload with the largest
    payloads, WARN at least when ``stale`` (how old the joint state is) is given."""
    statuses = [_joint_status(check, j, node_name, warn_use) for j in range(len(check.joint_names))]
    figures = check.payload_figures()
    verdict = "over the limit at " + ", ".join(check.over) if check.over else "OK"
    message = f"{figures['payload mass [kg]']} kg: {verdict}"
    level = max(status.level for status in statuses)
    if stale is not None:
        level, message = max(level, WARN), f"{message}; stale joint_states"
        figures["stale joint_states"] = stale
    summary = DiagnosticStatus(
        level=level, name=f"{node_name}: payload", hardware_id=node_name, message=message,
        values=_key_values(figures),
    )
    return statuses + [summary]


def _joint_status(check: PayloadCheck, j: int, node_name: str, warn_use: float) -> DiagnosticStatus:
    figures = check.joint_figures(j)
    limit = check.limit[j]
    uses = {"worst use": check.worst_use[j], **({} if check.use is None else {"use now": check.use[j]})}
    most = max(uses, key=uses.get)
    if not check.within[j]:
        level = ERROR
    elif math.isfinite(limit):
        level = WARN if uses[most] >= warn_use else OK
    else:
        level = WARN if j in check.loaded_without_limit else OK
    if math.isfinite(limit):
        message = f"{figures[most]} of its {figures['limit [N m]']} N m limit"
    elif level == WARN:
        message = check.no_limit_note(j)
    else:
        message = figures["limit source"]
    return DiagnosticStatus(
        level=level, name=f"{node_name}: {check.joint_names[j]}", hardware_id=node_name,
        message=message, values=_key_values(figures),
    )


def _key_values(figures: dict[str, str]) -> list[KeyValue]:
    return [KeyValue(key=key, value=value) for key, value in figures.items()]
