"""A joint state read once, into one value (``JointSample``), from any message with the fields
of sensor_msgs/JointState (a JointState, or ``core.io.joint_state_cdr``'s view of its bytes);
and a JointTrajectory's points into arrays. No ROS: the nodes hand their messages in."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from irb140_dynamics.core.io.stamps import seconds
from irb140_dynamics.core.model.joint_order import BadMessage, JointOrder


def pick(values, index: list[int], field: str, length: int, required: bool) -> list[float]:
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


def read_joint_sample(msg, order: JointOrder, now: Callable[[], float]) -> JointSample:
    """The sample of a JointState, its joints matched by name (in any order, others ignored;
    a message without names only if its length fits the model); ``now()`` [s] is read only
    for an unstamped message. BadMessage (NotForThisModel for other joints only) if unusable."""
    index, length = order.for_values(msg.name, len(msg.position))
    q = pick(msg.position, index, "position", length, required=True)
    qd = pick(msg.velocity, index, "velocity", length, required=False)
    effort, bad_effort = msg.effort, None
    if len(effort) == 0:
        effort = None
    elif len(effort) != length:
        raise BadMessage("length_mismatch", f"effort has {len(effort)} values for {length} joints")
    else:
        try:
            effort = pick(effort, index, "effort", length, required=True)
        except BadMessage as error:
            effort, bad_effort = None, BadMessage("effort_not_finite", str(error))
    stamp = msg.header.stamp
    t = seconds(stamp.sec, stamp.nanosec) or now()
    return JointSample(stamp, t, np.array(q), np.array(qd), effort, bad_effort)


def read_trajectory_points(msg, order: JointOrder):
    """(times, Q, QD, QDD or None) of a JointTrajectory's points, in the model's joint order
    (by time_from_start). Velocities count as zero when empty; accelerations are given on
    every point or on none."""
    times, Q, QD, QDD = [], [], [], []
    for k, point in enumerate(msg.points):
        index, length = order.for_values(msg.joint_names, len(point.positions))
        Q.append(pick(point.positions, index, f"points[{k}].positions", length, required=True))
        QD.append(pick(point.velocities, index, f"points[{k}].velocities", length, required=False))
        if len(point.accelerations):
            QDD.append(pick(point.accelerations, index, f"points[{k}].accelerations", length, required=True))
        times.append(seconds(point.time_from_start.sec, point.time_from_start.nanosec))
    if QDD and len(QDD) != len(Q):
        raise BadMessage("length_mismatch", "accelerations must be given on every point or on none")
    return np.array(times), np.array(Q), np.array(QD), np.array(QDD) if QDD else None
