"""What `identify --payload-only` prints and writes: the payload's values with their
standard deviations, and the arm's parameter file carrying the identified payload."""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np

from irb140_dynamics.core.errors import counted
from irb140_dynamics.core.io.params_file import parameter_file_text
from irb140_dynamics.core.model.rigid_body import inertia_matrix
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.identification.payload import PayloadFit

_INERTIA_NAMES = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def payload_summary(fit: PayloadFit, arm: RobotModel) -> str:
    """The payload (flange frame, inertia about its CoM in flange axes) with standard
    deviations, its principal moments, and how well it explains the torques."""
    payload, std = fit.payload, fit.std
    lines = [
        "payload (flange frame; inertia about its CoM, flange axes; +- one standard deviation):",
        f"  mass  {payload.mass:.6g} +- {std['mass']:.2g} kg",
    ]
    for axis, value, deviation in zip("xyz", payload.com, std["com"]):
        lines.append(f"  com.{axis} {value: .6g} +- {deviation:.2g} m")
    for name, value, deviation in zip(_INERTIA_NAMES, payload.inertia, std["inertia"]):
        lines.append(f"  {name:5s} {value: .6g} +- {deviation:.2g} kg m^2")
    moments = np.linalg.eigvalsh(inertia_matrix(payload.inertia))
    lines.append(f"  principal moments about the CoM: {', '.join(f'{m:.6g}' for m in moments)} kg m^2")
    if fit.misfit > 0.0:
        lines.append(
            f"  (the least-squares estimate is no physical body: this is the nearest one, "
            f"{np.sqrt(fit.misfit):.2g} standard deviations away)"
        )
    residual = ", ".join(
        f"{name} {rms:.3g} N m ({counted(int(rows), 'row')})"
        for name, rms, rows in zip(arm.joint_names, fit.residual_rms, fit.rows)
    )
    lines.append(f"residual RMS torque per joint: {residual}")
    return "\n".join(lines)


def payload_file(fit: PayloadFit, arm: RobotModel, command: str, urdf: str | None = None) -> str:
    """The arm's parameter file with ``payload.*`` the identified payload, the summary as
    comments; ``urdf``: the URDF the arm came from (its joints are then in URDF form, which
    the nodes do not declare: the comments say how they take the payload)."""
    date = datetime.now(UTC).isoformat(timespec="seconds")
    if urdf is None:
        use = ["Load it into the nodes and tools with --params-file. Units: SI (m, kg, kg m^2)."]
    else:
        use = [
            "Load it into the tools with --params-file. Units: SI (m, kg, kg m^2). The nodes declare DH",
            f"joints only: the nodes take this arm from its URDF (model.source: robot_description, {urdf})",
            "and payload.* from this file (its per-joint entries are then reported unknown and ignored).",
        ]
    comments = [
        f"payload identified by irb140_dynamics `identify --payload-only` on {date}:",
        f"  {command}",
        "The arm's own parameters are those it was given; payload.* is identified.",
        *use,
        "",
        *payload_summary(fit, arm).splitlines(),
        "",
    ]
    return parameter_file_text(arm.with_payload(fit.payload).to_params(), comments)
