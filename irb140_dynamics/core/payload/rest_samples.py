"""Rest samples from a stream of joint states, and the payload estimate they give.

``RestDetector`` averages joint states while the arm rests, one sample per distinct pose.
``PayloadEstimator`` keeps one for a node: it takes each joint state, estimates the payload
from the samples (``mass_com_estimation``), its refusal naming first what the joint states
lack, forgets them on request, and sums up what it holds for diagnostics.

"At rest" is slower than a rest velocity, where the model's tanh-smoothed Coulomb friction
is far from zero: the detector takes the model's friction at each joint state's measured
velocity off its efforts (nothing at qd = 0).
"""

from __future__ import annotations

import math

import numpy as np

from irb140_dynamics.core.model.friction import JointFriction
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.payload.mass_com_estimation import (
    EstimationError,
    PayloadEstimate,
    RestSample,
    estimate_payload,
)

NO_EFFORT_ADVICE = "the driver must publish JointState.effort (the measured joint torques)"


class PayloadEstimator:
    """The rest samples of a stream of joint states, and the last estimate from them."""

    def __init__(self, rest_velocity: float, rest_time: float, friction: JointFriction | None = None):
        self.detector = RestDetector(rest_velocity, rest_time, friction=friction)
        self.last: PayloadEstimate | None = None
        self._efforts_missing = False  # the latest joint state had none

    def configure(self, rest_velocity: float, rest_time: float, friction: JointFriction | None) -> None:
        """The settings in force; ``friction``: the model's, taken off the efforts at rest."""
        detector = self.detector
        detector.rest_velocity, detector.rest_time, detector.friction = rest_velocity, rest_time, friction

    def take(self, t: float, q, qd, effort) -> str | None:
        """One joint state at ``t`` [s] (``effort`` None when it has none). A non-finite effort
        counts as none; one too large to average leaves the state out. What was left out, in
        words, or None."""
        left_out = None
        if effort is not None and not all(map(math.isfinite, effort)):
            left_out, effort = f"an effort not finite, taken as none: {[float(x) for x in effort]}", None
        self._efforts_missing = effort is None
        try:
            self.detector.update(t, q, qd, effort)
        except ValueError as error:
            return f"a joint state left out ({error})"
        return left_out

    def estimate(self, model: RobotModel) -> tuple[PayloadEstimate, str | None]:
        """(The payload from the rests so far, a rest going on included; a note when some
        rests had no effort, or None). EstimationError names the missing efforts first: they
        are what to fix."""
        self.detector.flush()
        missing = self._missing_effort()
        try:
            self.last = estimate_payload(model, self.detector.samples)
        except EstimationError as error:
            if missing is None:
                raise
            raise EstimationError(f"{missing}; {error}" if self.detector.samples else missing) from None
        return self.last, missing if self.detector.without_effort else None

    def clear(self) -> str:
        """Forget the samples and the last estimate (of what may no longer be mounted): what
        was forgotten, in words."""
        count, estimate = len(self.detector.samples), self.last is not None
        self.detector.clear()
        self.last = None
        return f"forgot {count} rest samples" + (" and the last estimate" if estimate else "")

    def summary(self) -> tuple[str, dict[str, str]]:
        """(message, figures by name): the samples kept and the last estimate."""
        samples = len(self.detector.samples)
        message, figures = f"{samples} rest samples", {"rest samples": str(samples)}
        if self.last is not None:
            message += f"; last estimate: {self.last.summary()}"
            figures["estimated mass [kg]"] = f"{self.last.mass:.3f}"
            figures["estimated CoM [m]"] = ", ".join(f"{x:.4f}" for x in self.last.com)
        return message, figures

    def _missing_effort(self) -> str | None:
        """What the joint states' missing efforts cost, or None."""
        poses = len(self.detector.without_effort)
        if poses:
            return f"{poses} rest pose{'s' if poses > 1 else ''} had no effort in joint_states: {NO_EFFORT_ADVICE}"
        if self._efforts_missing and not self.detector.samples:
            return f"joint_states carry no effort: {NO_EFFORT_ADVICE}"
        return None


class RestDetector:
    """Averages joint states while every joint is slower than ``rest_velocity`` [rad/s]; a rest
    of at least ``rest_time`` [s] becomes a sample, one per distinct pose (a pose within
    ``same_pose`` [rad] of an earlier one replaces it). A joint state the rest velocity cannot
    reach from the one before (farther than ``same_pose`` plus ``rest_velocity`` times the
    time since, none for an older stamp) ends the rest and starts another: a driver reporting
    zero velocities, or a gap in the stream, never averages two poses into one.

    ``friction`` (the model's JointFriction, or None): its torque at each joint state's
    measured velocity is taken off that state's efforts before averaging. Inside the rest band
    the tanh-smoothed Coulomb friction is not small (with the default smoothing velocity, 76 %
    of its level at 0.01 rad/s, 96 % at 0.02); at qd = 0 it is exactly 0. A rest whose joint states carry no effort
    is no sample; its pose is counted in ``without_effort`` (until a sample of it comes)."""

    def __init__(
        self,
        rest_velocity: float,
        rest_time: float,
        same_pose: float = 1e-3,
        max_samples: int = 100,
        friction: JointFriction | None = None,
    ):
        self.rest_velocity, self.rest_time = rest_velocity, rest_time
        self.same_pose, self.max_samples = same_pose, max_samples
        self.friction = friction
        self.samples: list[RestSample] = []
        self.without_effort: list[np.ndarray] = []  # poses of rests without effort
        self._restart()

    def clear(self) -> None:
        self.samples, self.without_effort = [], []
        self._restart()

    def _restart(self) -> None:
        self._start = self._last = None  # times of the current rest's first and last joint states
        self._q_last = None  # the current rest's last pose
        self._sum_q = self._sum_effort = self._sum_squares = None
        self._count = 0
        self._has_effort = True  # of the current rest's joint states (a change ends the rest)

    def update(self, t: float, q, qd, effort) -> bool:
        """Take one joint state (effort may be None); True when a rest sample was added.
        ValueError, nothing taken, for an effort too large to average (its square overflows)."""
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        if effort is not None:
            effort = np.asarray(effort, dtype=float)
            with np.errstate(over="ignore", invalid="ignore"):
                if not np.isfinite(effort * effort).all():
                    raise ValueError(f"effort {effort.tolist()} N m: too large to average")
        moving = np.max(np.abs(qd)) >= self.rest_velocity
        added = False
        if moving or (self._start is not None and (self._has_effort != (effort is not None) or self._jumped(t, q))):
            added = self._close()
            self._restart()
        if moving:
            return added
        if self._start is None:
            self._start, self._has_effort = t, effort is not None
            self._sum_q, self._sum_effort, self._sum_squares = (np.zeros_like(q) for _ in range(3))
        self._sum_q += q
        if effort is not None:
            if self.friction is not None:
                effort = effort - self.friction.torques(qd)
            self._sum_effort += effort
            self._sum_squares += effort**2
        self._count += 1
        self._last, self._q_last = max(t, self._last if self._last is not None else t), q
        return added

    def _jumped(self, t: float, q: np.ndarray) -> bool:
        """Whether q at t is beyond the rest velocity's reach from the rest's last joint state."""
        reach = self.same_pose + self.rest_velocity * max(t - self._last, 0.0)
        return float(np.max(np.abs(q - self._q_last))) > reach

    def _close(self) -> bool:
        if self._start is None or self._last - self._start < self.rest_time:
            return False
        n = self._count
        q = self._sum_q / n
        if not self._has_effort:
            self.without_effort = self._others(self.without_effort, q, lambda p: p) + [q]
            return False
        mean = self._sum_effort / n
        error = None
        if n > 1:
            variance = np.maximum(self._sum_squares / n - mean**2, 0.0) * n / (n - 1)
            error = np.sqrt(variance / n)
        self.samples = self._others(self.samples, q, lambda s: s.q) + [RestSample(q, mean, n, error)]
        self.without_effort = self._others(self.without_effort, q, lambda p: p)
        return True

    def _others(self, kept: list, q: np.ndarray, pose_of) -> list:
        """``kept`` without the entries of pose q, leaving room for one more (at most max_samples)."""
        others = [x for x in kept if np.max(np.abs(pose_of(x) - q)) > self.same_pose]
        return others[len(others) - self.max_samples + 1 :] if len(others) >= self.max_samples else others

    def flush(self) -> bool:
        """Close a rest still going on (e.g. before an estimate): True if it became a sample."""
        added = self._close()
        if added:
            self._restart()
        return added
