"""Collisions from measured efforts: the momentum observer's residual r (the external joint
torques [N m]) against a threshold per joint.

A joint collides while |r_j| exceeds its threshold (0 = off). ``report`` says what happened
since the last report, so that a collision shorter than the reporting period still shows:
now, or the peak |r_j| of each joint over its threshold since.
"""

from __future__ import annotations

from typing import NamedTuple

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.monitoring.observer import MomentumObserver

OBSERVER_GAP = 0.1  # s: a longer gap between samples restarts the observer
DEFAULT_GAIN = 100.0  # 1/s: the observer's gain K (id_node's collision.observer_gain, calibrate_collision's)
MIN_GAIN, MAX_GAIN = 1e-3, 1e4  # 1/s: the gains accepted
RESTARTS = {  # MomentumObserver.restarted: what restarted it
    "gap": f"a gap of more than {OBSERVER_GAP:g} s between joint_states stamps",
    "repeated_stamp": "a repeated joint_states stamp",
    "older_stamp": "a joint_states stamp older than the one before",
}


class Report(NamedTuple):
    collided: bool  # colliding now, or since the last report
    message: str
    values: dict[str, str]


class CollisionMonitor:
    """The observer over a stream of samples with efforts; which joints collide."""

    def __init__(self):
        self.names: tuple[str, ...] = ()
        self.residual: list[float] | None = None  # of the last sample with efforts
        self.colliding: list[int] = []  # indices of the joints over their thresholds
        self._peaks: list[float] = []  # N m: the largest |r_j| over threshold since the last report

    def use(self, model: RobotModel, gain: float, thresholds) -> None:
        """A new model or new settings: the observer starts again (r kept for joints of the same names)."""
        if model.joint_names != self.names:
            self.names, self.residual, self._peaks = model.joint_names, None, [0.0] * model.n
        self.observer = MomentumObserver(model, gain, OBSERVER_GAP)
        self._thresholds = [float(x) for x in thresholds]

    def reset(self) -> None:
        self.observer.reset()

    @property
    def restarted(self) -> str | None:
        """What restarted the observer at the last sample (a key of RESTARTS), or None."""
        return self.observer.restarted

    def update(self, t: float, q, qd, effort, g, terms=None) -> list[float]:
        """r after one sample (see MomentumObserver.advance); ValueError (observer reset) if
        it is not finite."""
        r = self.residual = self.observer.advance(t, q, qd, effort, g, terms)
        self.colliding = colliding = [
            j for j, (x, limit) in enumerate(zip(r, self._thresholds)) if 0.0 < limit < abs(x)
        ]
        peaks = self._peaks
        for j in colliding:
            peaks[j] = max(peaks[j], abs(r[j]))
        return r

    def report(self) -> Report:
        """Colliding now or since the last report (naming joints and torques: now, or the
        peak |r_j| since); starts a new period."""
        names, r, peaks = self.names, self.residual, self._peaks
        self._peaks = [0.0] * len(names)
        if r is None:
            return Report(False, "no efforts received: observer idle", {})
        earlier = [j for j, peak in enumerate(peaks) if peak > 0.0 and j not in self.colliding]
        since = ", ".join(f"{names[j]} {peaks[j]:.2f} N m" for j in earlier)
        if self.colliding:
            message = "collision: " + ", ".join(f"{names[j]} {r[j]:.2f} N m" for j in self.colliding)
            message += f"; since last report: {since}" if earlier else ""
        else:
            message = f"collision since last report: {since}" if earlier else "no collision"
        values = {f"{name} external torque [N m]": f"{x:.3f}" for name, x in zip(names, r)}
        for j, peak in enumerate(peaks):
            if peak > 0.0:
                values[f"{names[j]} peak |external torque| since last report [N m]"] = f"{peak:.3f}"
        return Report(bool(self.colliding or earlier), message, values)
