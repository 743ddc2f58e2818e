"""trajectory_msgs/JointTrajectory to the core's Trajectory (and back: ros.messages), and a
report as one diagnostic_msgs/DiagnosticStatus (core.trajectories.checker: its level, figures)."""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from trajectory_msgs.msg import JointTrajectory

from irb140_dynamics.core.trajectories import Trajectory

LEVELS = {"ok": DiagnosticStatus.OK, "warn": DiagnosticStatus.WARN, "error": DiagnosticStatus.ERROR}


def trajectory_of(msg: JointTrajectory, joint_names) -> Trajectory:
    """The message's points in the model's joint order (TrajectoryError naming the point)."""
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


def status(level: str, name: str, hardware_id: str, message: str, figures=()) -> DiagnosticStatus:
    """A DiagnosticStatus of ``level`` ('ok', 'warn', 'error') with (key, value) ``figures``."""
    values = [KeyValue(key=key, value=value) for key, value in figures]
    return DiagnosticStatus(level=LEVELS[level], name=name, hardware_id=hardware_id, message=message, values=values)
