"""Statuses for /diagnostics: a payload check (its key-values the figures of the ~/check
report), and the message counts of id_node."""

from __future__ import annotations

import math

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue

from irb140_dynamics.core.payload import PayloadCheck

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


def payload_statuses(
    check: PayloadCheck, node_name: str, warn_use: float, stale: str | None = None
) -> list[DiagnosticStatus]:
    """One status per joint (OK; WARN from ``warn_use`` %, when the payload loads a joint
    without a limit, or when its proof cannot tell whether it is within its limit; ERROR
    proven over its limit), then one for the payload with the largest payloads and the
    verdict (``PayloadCheck.headline``), WARN at least when ``stale`` (how old the joint
    state is) is given."""
    statuses = [_joint_status(check, j, node_name, warn_use) for j in range(len(check.joint_names))]
    figures = check.payload_figures()
    message = check.headline()
    level = max(status.level for status in statuses)
    if stale is not None:
        level, message = max(level, WARN), f"{message}; stale joint_states"
        figures["stale joint_states"] = stale
    summary = DiagnosticStatus(
        level=level,
        name=f"{node_name}: payload",
        hardware_id=node_name,
        message=message,
        values=[KeyValue(key=key, value=value) for key, value in figures.items()],
    )
    return statuses + [summary]


def _joint_status(check: PayloadCheck, j: int, node_name: str, warn_use: float) -> DiagnosticStatus:
    figures = check.joint_figures(j)
    limit = check.limit[j]
    uses = {"worst use": check.worst_use[j], **({} if check.use is None else {"use now": check.use[j]})}
    most = max(uses, key=uses.get)
    if check.beyond[j]:
        level = ERROR
    elif not check.within[j]:
        level = WARN
    elif math.isfinite(limit):
        level = WARN if uses[most] >= warn_use else OK
    else:
        level = WARN if j in check.loaded_without_limit else OK
    if not check.beyond[j] and not check.within[j]:
        message = (
            f"unproven: {figures[most]} of its {figures['limit [N m]']} N m limit by its bound: {check.unfinished}"
        )
    elif math.isfinite(limit):
        message = f"{figures[most]} of its {figures['limit [N m]']} N m limit"
    elif level == WARN:
        message = check.no_limit_note(j)
    else:
        message = figures["limit source"]
    return DiagnosticStatus(
        level=level,
        name=f"{node_name}: {check.joint_names[j]}",
        hardware_id=node_name,
        message=message,
        values=[KeyValue(key=key, value=value) for key, value in figures.items()],
    )


def message_status(node_name: str, hardware_id: str, counts, recent, parameters, waiting: bool) -> DiagnosticStatus:
    """The counts per topic and kind (``recent``: those of the last period): ERROR when
    accepted parameters could not be applied (``parameters``: the node's LiveParameters),
    WARN while waiting for a model, while messages are dropped or joint_states stop coming."""
    status = DiagnosticStatus(name=f"{node_name}: messages", hardware_id=hardware_id)
    dropped = sum(n for key, n in recent.items() if key.endswith((".dropped", ".errors")))
    in_force = parameters.status()
    if parameters.failure is not None:
        status.level, status.message = ERROR, in_force
    elif waiting:
        status.level, status.message = WARN, "waiting for the model (robot_description topic)"
    elif dropped:
        status.level, status.message = WARN, f"{dropped} messages dropped in the last second"
    elif counts["joint_states.received"] and not recent["joint_states.received"]:
        status.level, status.message = WARN, "no joint_states in the last second"
    else:
        status.level, status.message = OK, f"{recent['torques.published']} torque messages in the last second"
    status.values = [KeyValue(key=key, value=str(value)) for key, value in sorted(counts.items())]
    status.values.append(KeyValue(key="parameters", value=in_force or "in force"))
    return status
