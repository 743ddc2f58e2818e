"""Statuses for /diagnostics: a payload check (its key-values the figures of the ~/check
report), and the message counts of id_node."""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue

from irb140_dynamics.core.payload import PayloadCheck

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR
LEVELS = {"OK": OK, "WARN": WARN, "ERROR": ERROR}


def payload_statuses(
    check: PayloadCheck, node_name: str, warn_use: float, stale: str | None = None
) -> list[DiagnosticStatus]:
    """One status per joint (``PayloadCheck.joint_status``), then one for the payload: its
    largest payloads and the verdict (``PayloadCheck.headline``), WARN at least when
    ``stale`` (how old the joint state is) is given."""
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
    level, message = check.joint_status(j, warn_use)
    return DiagnosticStatus(
        level=LEVELS[level],
        name=f"{node_name}: {check.joint_names[j]}",
        hardware_id=node_name,
        message=message,
        values=[KeyValue(key=key, value=value) for key, value in check.joint_figures(j).items()],
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
