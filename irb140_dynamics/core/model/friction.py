"""Joint friction: viscous plus smoothed Coulomb, per joint.

    tau_f,i = viscous_i qd_i + coulomb_i tanh(qd_i / v_s)       [N m]

Coulomb friction is a step at zero velocity; the tanh makes it smooth, so that a torque
computed from a noisy velocity near zero does not chatter between +-coulomb. v_s, the
smoothing velocity (model parameter ``friction.smoothing_velocity``, default 0.01 rad/s), is
where it reaches tanh(1) = 76 % of its level; at 3 v_s it is 99.5 %. Friction is part of
``rnea`` (so of the feed-forward) and of ``forward_dynamics``, not of ``gravity``,
``coriolis`` or the static payload analysis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class JointFriction:
    viscous: np.ndarray  # (n,) N m s/rad
    coulomb: np.ndarray  # (n,) N m
    smoothing_velocity: float  # rad/s

    @classmethod
    def of(cls, model) -> JointFriction:
        return cls(
            np.array([j.friction.viscous for j in model.joints]),
            np.array([j.friction.coulomb for j in model.joints]),
            model.smoothing_velocity,
        )

    def coulomb_shape(self, qd) -> np.ndarray:
        """tanh(qd / v_s): the Coulomb torque per N m of level, (n,) or (N, n)."""
        return np.tanh(np.asarray(qd, dtype=float) / self.smoothing_velocity)

    def torques(self, qd) -> np.ndarray:
        """Friction torques for velocities qd shaped (n,) or (N, n)."""
        qd = np.asarray(qd, dtype=float)
        return self.viscous * qd + self.coulomb * self.coulomb_shape(qd)
