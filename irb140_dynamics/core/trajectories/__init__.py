"""Joint trajectories: reference motions and computed-torque control (``reference``), the
torques of a stream of measured states following one in time (``tracking``); a
JointTrajectory checked against the model's limits and re-timed time-optimally.

``message``: a JointTrajectory as the core sees it (times, positions and, per point, optional
velocities and accelerations), read from and written to the layout ``ros2 topic echo``
prints. ``interpolation``: sampled exactly as ros2_control's joint_trajectory_controller
interpolates it. ``limits``: the torque, velocity and acceleration limits (torque limits the
params file leaves at 0 derived as the payload check does). ``check``: per joint the peak
torque (RNEA with friction, armature and payload), velocity and acceleration against the
limits. ``retiming``: the time-optimal timing of the same path (``path``: the grid over it;
``topp``: reachability analysis). ``checker``: a model and its limits, built once, checking
and re-timing every trajectory a service is sent; a report's level, headline and figures.

May import: ``core.model``, the verbs in ``core.dynamics``, ``core.payload`` (limits), ``core.monitoring``
(the observer's terms, the velocity filter). No ROS.
"""

from .check import JointPeak, TrajectoryReport, check_trajectory
from .checker import TrajectoryChecker
from .limits import Limits, torque_limit_notes, trajectory_limits
from .message import Trajectory, TrajectoryError
from .retiming import Retimed, retime

__all__ = [
    "torque_limit_notes",
    "JointPeak",
    "Limits",
    "Retimed",
    "Trajectory",
    "TrajectoryChecker",
    "TrajectoryError",
    "TrajectoryReport",
    "check_trajectory",
    "retime",
    "trajectory_limits",
]
