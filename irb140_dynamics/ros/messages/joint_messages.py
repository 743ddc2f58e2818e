"""Joint messages <-> arrays in the model's joint order, and the checks a message must pass."""

from __future__ import annotations

import math

import numpy as np
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from irb140_dynamics.core.io.stamps import seconds
from irb140_dynamics.core.model.joint_order import BadMessage, JointOrder, NotForThisModel  # noqa: F401  (the nodes' too)


def core_result(function, model, *state):
    """``function(model, *state)``; the core's refusal (ValueError: a state too large for
    the model, the torques not finite) as BadMessage non_finite_torques."""
    try:
        return function(model, *state)
    except ValueError as error:
        raise BadMessage("non_finite_torques", str(error)) from None


def finite_torques(function, model, *state):
    """``function(model, *state)`` (rnea, gravity) when all its torques are finite, else
    BadMessage non_finite_torques (an absurd but finite state can overflow the model's
    sums; the core may return the non-finite torques or refuse them with ValueError)."""
    tau = core_result(function, model, *state)
    values = tau.tolist() if type(tau) is np.ndarray else tau  # a sum of floats: a fraction of NumPy's
    if not (math.isfinite(sum(values)) or all(map(math.isfinite, values))):
        raise BadMessage("non_finite_torques", f"the model gives {[float(x) for x in tau]}")
    return tau


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


def read_joint_state(msg: JointState, order: JointOrder) -> tuple[list[float], list[float]]:
    """(q, qd) of the model's joints; missing velocities count as zero.

    Joints are matched by name, in any order, others ignored; a message without names is
    taken positionally only if its length matches the model. ``effort`` is not used, but
    its length must fit too. Raises NotForThisModel for a message about other joints only.
    """
    index, length = order.for_values(msg.name, len(msg.position))
    q = _pick(msg.position, index, "position", length, required=True)
    qd = _pick(msg.velocity, index, "velocity", length, required=False)
    if len(msg.effort) not in (0, length):
        raise BadMessage("length_mismatch", f"effort has {len(msg.effort)} values for {length} joints")
    return q, qd


def read_effort(msg: JointState, order: JointOrder) -> list[float] | None:
    """The efforts of the model's joints, None when the message has none (BadMessage
    ``effort_not_finite`` for a NaN or infinite one). Call after read_joint_state."""
    if len(msg.effort) == 0:
        return None
    index, length = order.for_values(msg.name, len(msg.position))
    try:
        return _pick(msg.effort, index, "effort", length, required=True)
    except BadMessage as error:
        raise BadMessage("effort_not_finite", str(error)) from None


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


def publish_efforts(publisher, message, stamp, effort) -> None:
    """Publish ``message`` (a ros.messages.joint_state_cdr.EffortMessage: fixed names) with ``stamp``
    and ``effort`` on a ListenedPublisher, if anything subscribes: a message nobody has
    subscribed to would cost its serialization for nothing."""
    if publisher.subscribers:
        publisher.publish(message.serialize(stamp, effort))
