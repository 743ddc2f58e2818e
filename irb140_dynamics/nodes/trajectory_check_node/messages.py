"""trajectory_msgs/JointTrajectory to and from the core's Trajectory, and a trajectory
report as one diagnostic_msgs/DiagnosticStatus (one KeyValue per joint and limit)."""

from __future__ import annotations

from builtin_interfaces.msg import Duration
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from irb140_dynamics.core.io.stamps import sec_nanosec
from irb140_dynamics.core.trajectories import Trajectory, TrajectoryReport

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


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


def trajectory_message(tr: Trajectory, frame_id: str = "") -> JointTrajectory:
    """The trajectory as a message (velocities and accelerations where the points carry them)."""
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


def report_status(report: TrajectoryReport, name: str, hardware_id: str, warn_use: float, notes=()) -> DiagnosticStatus:
    """OK; WARN when a limit is used more than ``warn_use`` %; ERROR over a limit."""
    worst = report.worst
    level = ERROR if not report.ok else WARN if 100 * worst.ratio >= warn_use else OK
    verdict = "within every limit" if report.ok else "OVER A LIMIT"
    values = [KeyValue(key="duration [s]", value=f"{report.duration:.6f}")]
    values += [KeyValue(key="note", value=note) for note in notes]
    values += [KeyValue(key=f"{p.joint} {p.quantity}", value=p.line().split(": ", 1)[1]) for p in report.peaks]
    message = f"{report.duration:.3f} s, {verdict}; worst: {worst.line()}"
    return DiagnosticStatus(level=level, name=name, hardware_id=hardware_id, message=message, values=values)


def error_status(reason: str, name: str, hardware_id: str) -> DiagnosticStatus:
    return DiagnosticStatus(level=ERROR, name=name, hardware_id=hardware_id, message=reason)
