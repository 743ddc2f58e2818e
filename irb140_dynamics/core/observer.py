"""External joint torques from the measured efforts: the generalized momentum observer.

With p = M(q) qd the generalized momentum, the equations of motion give

    dp/dt = tau + tau_ext + C(q, qd)^T qd - g(q) - tau_f(qd)

(De Luca et al. 2003). The observer's residual

    r(t) = K (p(t) - p(0) - integral_0^t (tau + C^T qd - g - tau_f + r) ds)

obeys dr/dt = K (tau_ext - r): a first-order low-pass of the external torques with time
constant 1/K [s], needing no acceleration. C^T qd is dT/dq, the gradient of the kinetic
energy T = 1/2 qd^T M qd, generated exactly (dual numbers) like the other kernels.

Units: N m, s, 1/s. Samples come with their time; a gap longer than ``max_gap``, a repeated
or an older time resets the observer (the next sample starts it again at r = 0).
"""

from __future__ import annotations

import numpy as np

from .algorithms import add, cross, dot, inertia_times, scale, to_child, turns
from .dual import dual_angles, partial
from .dynamics import gravity
from .states import state
from .model import RobotModel


def kinetic_energy(links, cs, qd):
    """T = sum over links of 1/2 m v.v + v.(w x h) + 1/2 w.(I w), v the velocity of o_i."""
    rots = turns(links, cs)
    w, v = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    energy = 0.0
    for link, rot, qd_i in zip(links, rots, qd):
        if link.p0 is not None:
            v = add(v, cross(w, link.p0))
        w_parent = to_child(link, rot, w)
        w = add(w_parent, scale(qd_i, link.b))
        v = add(to_child(link, rot, v), cross(w, link.p))
        energy = energy + 0.5 * (link.m * dot(v, v) + dot(w, inertia_times(link.I, w))) + dot(v, cross(w, link.h))
    return energy


def energy_gradient(links, cs, qd):
    """dT/dq = C(q, qd)^T qd, exact: T on dual numbers carrying d/dq_k."""
    T = kinetic_energy(links, dual_angles(cs), qd)
    return [partial(T, k) for k in range(len(links))]


class MomentumObserver:
    """The residual r ~ tau_ext [N m], updated sample by sample."""

    def __init__(self, model: RobotModel, gain: float, max_gap: float = 0.1):
        if not gain > 0.0:
            raise ValueError(f"gain: must be > 0 1/s, got {gain}")
        self.model, self.gain, self.max_gap = model, float(gain), float(max_gap)
        self.reset()

    def reset(self) -> None:
        """Forget the past: the next sample starts the observer again."""
        self.r = np.zeros(self.model.n)
        self._t = None

    def update(self, t: float, q, qd, tau, g=None) -> np.ndarray:
        """The residual after the sample (t [s], q, qd, tau measured): r, or zeros after a reset.

        ``g``: gravity(model, q) if the caller has it already. ValueError (and a reset) if a
        value is not finite.
        """
        n = self.model.n
        q, qd, tau = state(q, n, "q"), state(qd, n, "qd"), np.asarray(state(tau, n, "tau"))
        p, beta = self._momentum_terms(q, qd, g)
        drive = tau + beta
        if self._t is None or not 0.0 < t - self._t <= self.max_gap:
            self.r = np.zeros(n)
            self._t, self._p0, self._integral, self._drive = t, p, np.zeros(n), drive
            return self.r.copy()
        dt = t - self._t
        with np.errstate(over="ignore", invalid="ignore"):  # checked just below
            integral = self._integral + 0.5 * (drive + self._drive) * dt + self.r * dt
            r = self.gain * (p - self._p0 - integral)
        if not np.all(np.isfinite(r)):
            self.reset()
            raise ValueError(f"observer residual not finite: {r.tolist()}")
        self._t, self._integral, self._drive, self.r = t, integral, drive, r
        return r.copy()

    def _momentum_terms(self, q, qd, g=None) -> tuple[np.ndarray, np.ndarray]:
        """p = M qd and C^T qd - g - tau_f: what the observer integrates besides tau and r."""
        model = self.model
        p, ct_qd = np.split(np.array(model.kernels.momentum.scalar(q, qd)), 2)
        beta = ct_qd - (gravity(model, q) if g is None else g)
        if model.friction is not None:
            beta -= model.friction.torques(qd)
        return p, beta
