"""id_node's reference: a whole trajectory followed in time, and computed-torque control.

A ~/reference (trajectory_msgs/JointTrajectory) is sampled by time_from_start from its
start: header.stamp when set, else the time it arrived (node clock; as ros2_control's
joint_trajectory_controller): q, qd, qdd interpolated linearly between points, the last
point held after the end. Until a stamped start the arm holds its position as without a
reference. It is in force until reference_timeout after its last point
(0 = for ever); an empty trajectory lets it go.

With ``effort_commands.source: computed_torque`` the commands are

    tau = M(q) (qdd_ref + Kd (qd_ref - qd) + Kp (q_ref - q)) + C(q, qd) qd + g(q) + tau_f(qd_ref)

(core.trajectories.reference.computed_torque), with per-joint gains ``<joint>.kp`` [1/s^2] and
``<joint>.kd`` [1/s]; without a reference in force the arm holds the position measured
when it had none. ``~/tracking_error`` (sensor_msgs/JointState) publishes q_ref - q as
``position`` and qd_ref - qd as ``velocity`` while a reference is in force.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.trajectories.reference import Trajectory, computed_torque
from irb140_dynamics.ros.parameters.specs import Spec

MAX_GAIN = 1e6
DEFAULT_KP = 400.0  # 1/s^2: natural frequency 20 rad/s
DEFAULT_KD = 40.0  # 1/s: critically damped with it


def gain_specs(joint_names) -> list[Spec]:
    specs = []
    for name in joint_names:
        specs += [
            Spec(f"{name}.kp", DEFAULT_KP, "computed-torque position gain", "1/s^2", minimum=0.0, maximum=MAX_GAIN),
            Spec(f"{name}.kd", DEFAULT_KD, "computed-torque velocity gain", "1/s", minimum=0.0, maximum=MAX_GAIN),
        ]
    return specs


@dataclass(frozen=True, eq=False)
class Gains:
    kp: np.ndarray  # 1/s^2
    kd: np.ndarray  # 1/s


def build_gains(values: dict, joint_names) -> Gains:
    kp, kd = ([values[f"{name}.{kind}"] for name in joint_names] for kind in ("kp", "kd"))
    return Gains(np.array(kp, dtype=float), np.array(kd, dtype=float))


class ReferenceTracker:
    """The reference in force, and the hold position when there is none."""

    def __init__(self):
        self.clear()

    def clear(self) -> None:
        self._trajectory: Trajectory | None = None
        self._start = 0.0  # s, node clock
        self._hold = None

    @property
    def trajectory(self) -> Trajectory | None:
        return self._trajectory

    def follow(self, trajectory: Trajectory, start: float) -> None:
        """Follow ``trajectory`` from ``start`` [s, node clock] on."""
        self._trajectory, self._start = trajectory, start

    def sample(self, now: float, timeout: float):
        """(q, qd, qdd or None) of the reference in force at ``now`` [s], or None (none, not
        started yet, or let go)."""
        if self._trajectory is None:
            return None
        elapsed = now - self._start
        if elapsed < 0.0 or (timeout > 0.0 and elapsed > self._trajectory.duration + timeout):
            return None
        return self._trajectory.sample(elapsed)

    def command(self, model, q, qd, reference, gains: Gains) -> np.ndarray:
        """Computed-torque command at the measured (q, qd) toward ``reference`` (from
        ``sample``), or toward the held position when it is None."""
        if reference is None:
            if self._hold is None:
                self._hold = np.array(q, dtype=float)
            q_ref, qd_ref, qdd_ref = self._hold, np.zeros(len(q)), None
        else:
            self._hold = None
            q_ref, qd_ref, qdd_ref = reference
        return computed_torque(model, q, qd, q_ref, qd_ref, qdd_ref, gains.kp, gains.kd)
