"""Joint messages <-> arrays in the model's joint order, and the checks a message must pass."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from builtin_interfaces.msg import Duration
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from irb140_dynamics.core.io.stamps import sec_nanosec, seconds
from irb140_dynamics.core.model.joint_order import BadMessage, JointOrder, NotForThisModel, core_result, finite_torques
from irb140_dynamics.ros.messages.joint_state_cdr import read_joint_state_cdr

__all__ = [
    "BadMessage",
    "JointOrder",
    "NotForThisModel",
    "JointSample",
    "core_result",
    "finite_torques",
    "read_joint_sample",
    "read_trajectory",
    "trajectory_message",
    "trajectory_of",
]


def _pick(values, index: list[int], field: str, length: int, required: bool) -> list[float]:
    """The values of the model's joints, or zeros when the field is empty and optional."""
    if len(values) == 0 and not required:
        return [0.0] * len(index)
    if len(values) != length:
        raise BadMessage("length_mismatch", f"{field} has {len(values)} values for {length} joints")
    picked = [values[i] for i in index]
    if not all(map(math.isfinite, picked)):
        raise BadMessage("not_finite", f"{field} is not finite: {picked}")
    return picked


class JointSample(NamedTuple):
    """One joint state of the model's joints, read once."""

    stamp: object  # the header's stamp (sec, nanosec), as the answers carry it
    t: float  # s: the stamp; for an unstamped message, the time of arrival
    q: np.ndarray  # rad, float64 (what the native kernels take)
    qd: np.ndarray  # rad/s; zeros when the message has none
    effort: list[float] | None  # N m; None when the message has none, or bad_effort
    bad_effort: BadMessage | None  # efforts given but not finite (effort_not_finite): q and qd still hold


def read_joint_sample(msg: bytes | JointState, order: JointOrder, now: Callable[[], float]) -> JointSample:
    """The sample of a JointState or of its serialized bytes (read by joint_state_cdr), its
    joints matched by name (in any order, others ignored; a message without names only if
    its length fits the model); ``now()`` [s] is read only for an unstamped message.
    BadMessage (NotForThisModel for other joints only) if unusable."""
    if type(msg) is bytes:
        msg = read_joint_state_cdr(msg)
    index, length = order.for_values(msg.name, len(msg.position))
    q = _pick(msg.position, index, "position", length, required=True)
    qd = _pick(msg.velocity, index, "velocity", length, required=False)
    effort, bad_effort = msg.effort, None
    if len(effort) == 0:
        effort = None
    elif len(effort) != length:
        raise BadMessage("length_mismatch", f"effort has {len(effort)} values for {length} joints")
    else:
        try:
            effort = _pick(effort, index, "effort", length, required=True)
        except BadMessage as error:
            effort, bad_effort = None, BadMessage("effort_not_finite", str(error))
    stamp = msg.header.stamp
    t = seconds(stamp.sec, stamp.nanosec) or now()
    return JointSample(stamp, t, np.array(q), np.array(qd), effort, bad_effort)


def read_trajectory(msg: JointTrajectory, order: JointOrder):
    """The whole trajectory of a non-empty message as a core Trajectory (points by
    time_from_start). Velocities count as zero when empty; accelerations are given on
    every point or on none."""
    from irb140_dynamics.core.trajectories.reference import Trajectory

    times, Q, QD, QDD = [], [], [], []
    for k, point in enumerate(msg.points):
        index, length = order.for_values(msg.joint_names, len(point.positions))
        Q.append(_pick(point.positions, index, f"points[{k}].positions", length, required=True))
        QD.append(_pick(point.velocities, index, f"points[{k}].velocities", length, required=False))
        if len(point.accelerations):
            QDD.append(_pick(point.accelerations, index, f"points[{k}].accelerations", length, required=True))
        times.append(seconds(point.time_from_start.sec, point.time_from_start.nanosec))
    if QDD and len(QDD) != len(Q):
        raise BadMessage("length_mismatch", "accelerations must be given on every point or on none")
    try:
        return Trajectory(np.array(times), np.array(Q), np.array(QD), np.array(QDD) if QDD else None)
    except ValueError as error:
        raise BadMessage("bad_trajectory", str(error)) from None


def trajectory_of(msg: JointTrajectory, joint_names):
    """The message as a core.trajectories.Trajectory (checked, per point, as the controller
    takes it: core.trajectories.message), in the model's joint order; TrajectoryError
    naming the point."""
    from irb140_dynamics.core.trajectories.message import Trajectory

    points = [
        {
            "positions": list(p.positions),
            "velocities": list(p.velocities),
            "accelerations": list(p.accelerations),
            "time_from_start": {"sec": p.time_from_start.sec, "nanosec": p.time_from_start.nanosec},
        }
        for p in msg.points
    ]
    return Trajectory.from_message({"joint_names": list(msg.joint_names), "points": points}, joint_names)


def trajectory_message(tr, frame_id: str = "") -> JointTrajectory:
    """A core.trajectories.Trajectory as a message (velocities and accelerations on the
    points that carry them): trajectory_of, the other way."""
    msg = JointTrajectory(joint_names=list(tr.joint_names))
    msg.header.frame_id = frame_id
    for k in range(len(tr.t)):
        sec, nanosec = sec_nanosec(tr.t[k])
        msg.points.append(
            JointTrajectoryPoint(
                positions=tr.q[k].tolist(),
                velocities=tr.qd[k].tolist() if tr.has_qd[k] else [],
                accelerations=tr.qdd[k].tolist() if tr.has_qdd[k] else [],
                time_from_start=Duration(sec=sec, nanosec=nanosec),
            )
        )
    return msg
