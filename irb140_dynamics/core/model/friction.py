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

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np


@dataclass(frozen=True, eq=False)
class JointFriction:
    viscous: np.ndarray  # (n,) N m s/rad
    coulomb: np.ndarray  # (n,) N m
    smoothing_velocity: float  # rad/s

    @classmethod
    def of(cls, model) -> JointFriction:
        """The friction of the model's independent joints, a mimic joint's carried by the
        joint it follows (virtual work): m^2 v more viscous friction, c more Coulomb
        friction (its multiplier m is +-1 when it has Coulomb friction, see ``model``)."""
        viscous, coulomb = np.zeros(model.n), np.zeros(model.n)
        for joint, (k, multiplier, _) in zip(model.joints, model.coordinates):
            viscous[k] += multiplier * multiplier * joint.friction.viscous
            coulomb[k] += joint.friction.coulomb
        return cls(viscous, coulomb, model.smoothing_velocity)

    def coulomb_shape(self, qd) -> np.ndarray:
        """tanh(qd / v_s): the Coulomb torque per N m of level, (n,) or (N, n)."""
        return np.tanh(np.asarray(qd, dtype=float) / self.smoothing_velocity)

    @cached_property
    def _lists(self) -> tuple[list, list, bool]:
        return self.viscous.tolist(), self.coulomb.tolist(), bool(self.coulomb.any())

    def listed(self, qd: list) -> list:
        """The friction at one state, qd a list of floats: plain Python, a few times cheaper
        than NumPy for the few joints of an arm (equal to ``torques`` to rounding)."""
        viscous, coulomb, any_coulomb = self._lists
        if not any_coulomb:
            return [v * x for v, x in zip(viscous, qd)]
        s, tanh = self.smoothing_velocity, math.tanh
        return [v * x + c * tanh(x / s) for v, c, x in zip(viscous, coulomb, qd)]

    def added(self, tau, qd: list) -> list:
        """tau + the friction at qd (see ``listed``)."""
        return [t + f for t, f in zip(tau, self.listed(qd))]

    def torques(self, qd) -> np.ndarray:
        """Friction torques for velocities qd shaped (n,) or (N, n)."""
        qd = np.asarray(qd, dtype=float)
        return self.viscous * qd + self.coulomb * self.coulomb_shape(qd)
