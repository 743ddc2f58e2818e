"""Joint messages <-> arrays in the model's joint order, and the checks a message must pass."""

from __future__ import annotations

from collections.abc import Callable

from builtin_interfaces.msg import Duration
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from irb140_dynamics.core.io import joint_samples
from irb140_dynamics.core.io.joint_samples import JointSample
from irb140_dynamics.core.io.joint_state_cdr import JointStateView, is_plain, read_plain
from irb140_dynamics.core.io.stamps import sec_nanosec
from irb140_dynamics.core.model.joint_order import BadMessage, JointOrder, NotForThisModel, core_result, finite_torques

__all__ = [
    "BadMessage",
    "JointOrder",
    "NotForThisModel",
    "JointSample",
    "core_result",
    "finite_torques",
    "read_joint_sample",
    "read_joint_state_cdr",
    "read_trajectory",
    "trajectory_message",
    "trajectory_of",
]


def read_joint_state_cdr(raw: bytes) -> JointStateView | JointState:
    """The JointState ``raw`` serializes (BadMessage ``malformed`` if it does not): plain
    little-endian CDR read without rclpy (``core.io.joint_state_cdr``: a third of rclpy's cost
    per message, bench/bench_nodes.py), anything else by rclpy's deserializer."""
    if is_plain(raw):
        return read_plain(raw)
    try:
        return deserialize_message(raw, JointState)
    except Exception as error:  # noqa: BLE001  (rclpy raises its own kinds for bad bytes)
        raise BadMessage("malformed", f"undecodable joint state: {error}") from None


def read_joint_sample(msg: bytes | JointState, order: JointOrder, now: Callable[[], float]) -> JointSample:
    """The sample (``core.io.joint_samples``) of a JointState or of its serialized bytes."""
    return joint_samples.read_joint_sample(read_joint_state_cdr(msg) if type(msg) is bytes else msg, order, now)


def read_trajectory(msg: JointTrajectory, order: JointOrder):
    """The whole trajectory of a non-empty message as a core Trajectory (BadMessage if unusable)."""
    from irb140_dynamics.core.trajectories.reference import Trajectory

    times, Q, QD, QDD = joint_samples.read_trajectory_points(msg, order)
    try:
        return Trajectory(times, Q, QD, QDD)
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
