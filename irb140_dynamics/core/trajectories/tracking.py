"""Torques for a stream of measured joint states: feed-forward, gravity, and a command that
follows a reference in time.

Each measured state (t [s], q, qd) gives the feed-forward tau = rnea(q, qd, qdd) and g(q).
qdd is the reference's when one is in force, else zero (``zero``) or the measured
velocities differentiated (``differentiate``: core.monitoring.filters). With efforts
measured and no reference, one pass gives tau, g and the momentum observer's terms
(core.monitoring.observer.monitor_terms).

A reference (a Trajectory) is sampled by its time from its start, the last point held after
the end; it is in force until ``reference_timeout`` after its last point (0 = for ever). The
command (``source``) is the feed-forward, gravity, or computed torque

    tau = M(q) (qdd_ref + Kd (qd_ref - qd) + Kp (q_ref - q)) + C(q, qd) qd + g(q) + tau_f(qd_ref)

(reference.computed_torque, gains per joint), toward the position measured when no
reference is in force; a differentiated qdd never enters a command (it would feed the
measured acceleration back). A state that gives a torque not finite is refused
(BadMessage non_finite_torques), as is a differentiated qdd not finite.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from irb140_dynamics.core.dynamics import gravity, rnea
from irb140_dynamics.core.model.joint_order import BadMessage, core_result, finite_torques
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.monitoring.filters import VelocityDifferentiator
from irb140_dynamics.core.monitoring.observer import monitor_terms
from irb140_dynamics.core.trajectories.reference import Trajectory, computed_torque

ACCELERATION_MODES = ("zero", "differentiate")
EFFORT_SOURCES = ("feedforward", "gravity", "computed_torque")


@dataclass(frozen=True, eq=False)
class Gains:
    kp: np.ndarray  # 1/s^2
    kd: np.ndarray  # 1/s


class ReferenceTracker:
    """The reference in force, from its start [s], and the position held when there is none."""

    def __init__(self):
        self.clear()

    def clear(self) -> None:
        self.trajectory: Trajectory | None = None
        self.start = 0.0  # s
        self._hold = None

    def follow(self, trajectory: Trajectory, start: float) -> None:
        self.trajectory, self.start = trajectory, start

    def sample(self, now: float, timeout: float):
        """(q, qd, qdd or None) in force at ``now`` [s], or None (none, not started, let go)."""
        if self.trajectory is None:
            return None
        elapsed = now - self.start
        if elapsed < 0.0 or (timeout > 0.0 and elapsed > self.trajectory.duration + timeout):
            return None
        return self.trajectory.sample(elapsed)

    def command(self, model, q, qd, reference, gains: Gains) -> np.ndarray:
        """Computed torque at (q, qd) toward ``reference`` (from ``sample``), or toward the
        position held since there was none."""
        if reference is None:
            if self._hold is None:
                self._hold = np.array(q, dtype=float)
            q_ref, qd_ref, qdd_ref = self._hold, np.zeros(len(q)), None
        else:
            self._hold = None
            q_ref, qd_ref, qdd_ref = reference
        return computed_torque(model, q, qd, q_ref, qd_ref, qdd_ref, gains.kp, gains.kd)


class Torques(NamedTuple):
    tau: object  # N m: feed-forward
    g: object  # N m: gravity
    command: object  # N m, or None (no commands)
    reference: tuple | None  # (q, qd, qdd or None) in force, or None
    terms: list | None  # the observer's (p, beta) at the state, or None


class TorqueStream:
    """The torques of each state of one stream (see the module), under settings given by ``use``."""

    def __init__(self):
        self.tracker = ReferenceTracker()
        self.model: RobotModel | None = None
        self.differentiator: VelocityDifferentiator | None = None

    def use(self, model: RobotModel, mode: str, cutoff: float, timeout: float, source: str | None, gains) -> bool:
        """New settings (``source`` None: no commands). A model of other joints forgets the
        reference and the velocities seen. False if the reference held gives no finite
        torques under ``model`` (it is let go)."""
        if self.model is None or model.joint_names != self.model.joint_names:
            self.tracker.clear()
            self.differentiator, self._zeros = None, np.zeros(model.n)
        if self.differentiator is None or cutoff != self.cutoff:
            self.differentiator = VelocityDifferentiator(model.n, cutoff)
        self.model, self.mode, self.cutoff, self.timeout, self.source, self.gains = (
            model, mode, cutoff, timeout, source, gains,
        )  # fmt: skip
        held = self.tracker.trajectory
        if held is not None and not held.torques_finite(model):
            self.tracker.clear()
            return False
        return True

    def follow(self, trajectory: Trajectory, start: float) -> None:
        """Follow ``trajectory`` from ``start`` [s] if the model gives finite torques at every
        point, else BadMessage non_finite_torques."""
        if not trajectory.torques_finite(self.model):
            raise BadMessage("non_finite_torques", "the model gives no finite torques at some point")
        self.tracker.follow(trajectory, start)

    def torques(self, t: float, q, qd, observed: bool, now: Callable[[], float]) -> Torques:
        """The torques at (t [s], q, qd: float64 arrays), all finite, or BadMessage.
        ``observed``: efforts were measured (the observer's terms wanted); ``now()``, the
        clock references are followed by, read only while one is held."""
        model, tracker = self.model, self.tracker
        qdd = self._acceleration(t, qd)
        reference = None if tracker.trajectory is None else tracker.sample(now(), self.timeout)
        q_ff, qd_ff, qdd_ref = reference or (q, qd, None)
        try:
            terms = None
            if reference is None and observed:
                tau, g, *terms = core_result(monitor_terms, model, q, qd, qdd)  # refuses non-finite tau, g
            else:
                tau = finite_torques(rnea, model, q_ff, qd_ff, qdd if qdd_ref is None else qdd_ref)
                g = finite_torques(gravity, model, q)
            source, command = self.source, None
            if source == "gravity":
                command = g
            elif source == "computed_torque":
                command = finite_torques(tracker.command, model, q, qd, reference, self.gains)
            elif source is not None:
                differentiated = qdd_ref is None and self.mode == "differentiate"
                command = finite_torques(rnea, model, q_ff, qd_ff, self._zeros) if differentiated else tau
        except BadMessage:
            if self.mode == "differentiate":
                self.differentiator.reset()  # the estimate may be what overflowed: start afresh
            raise
        return Torques(tau, g, command, reference, terms)

    def _acceleration(self, t: float, qd):
        if self.mode == "zero":
            return self._zeros
        qdd = self.differentiator.update(t, qd.tolist())  # Python floats: an overflow is inf, no warning
        if not all(map(math.isfinite, qdd)):  # an absurd velocity jump overflowed the difference
            self.differentiator.reset()
            raise BadMessage("not_finite_acceleration", f"the differentiated velocities give {qdd}")
        return np.array(qdd)
