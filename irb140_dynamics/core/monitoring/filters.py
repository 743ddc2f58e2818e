"""Joint accelerations estimated from a stream of joint velocities."""

from __future__ import annotations

import math


class VelocityDifferentiator:
    """qdd from successive qd samples: a finite difference through a first-order low-pass.

    y_k = y_{k-1} + alpha (raw_k - y_{k-1}),  raw_k = (qd_k - qd_{k-1}) / dt,
    alpha = dt / (dt + 1 / (2 pi f_c)), f_c the cut-off frequency [Hz].

    A sample whose time does not move forward (a repeated or older stamp, e.g. from a
    second publisher) is skipped; after a gap longer than ``max_gap`` [s] the estimate
    starts again from zero.
    """

    def __init__(self, n: int, cutoff_hz: float, max_gap: float = 0.5):
        if not cutoff_hz > 0.0:
            raise ValueError(f"cutoff frequency must be > 0 Hz, got {cutoff_hz}")
        self.n, self.max_gap = n, max_gap
        self.time_constant = 1.0 / (2.0 * math.pi * cutoff_hz)
        self.reset()

    def reset(self) -> None:
        self._t = None
        self._qd = None
        self.qdd = [0.0] * self.n

    def update(self, t: float, qd) -> list[float]:
        """Take the velocities at time t [s]; return the filtered accelerations."""
        if self._t is not None and t <= self._t:
            return self.qdd
        if self._t is None or t - self._t > self.max_gap:
            self.reset()
        else:
            dt = t - self._t
            alpha = dt / (dt + self.time_constant)
            self.qdd = [y + alpha * ((v - v_prev) / dt - y) for y, v, v_prev in zip(self.qdd, qd, self._qd)]
        self._t, self._qd = t, list(qd)
        return self.qdd
