"""External joint torques from the measured efforts: the generalized momentum observer.

With p = M(q) qd the generalized momentum, the equations of motion give

    dp/dt = tau + tau_ext + C(q, qd)^T qd - g(q) - tau_f(qd)

(De Luca et al. 2003). The observer's residual

    r(t) = K (p(t) - p(0) - integral_0^t (tau + C^T qd - g - tau_f + r) ds)

obeys dr/dt = K (tau_ext - r): a first-order low-pass of the external torques with time
constant 1/K [s], needing no acceleration. C^T qd is dT/dq, the gradient of the kinetic
energy T = 1/2 qd^T M qd; ``momentum_terms`` gives it and p in two passes like RNEA's
(``energy_gradient``, T on dual numbers, is the definition it is tested against).

Units: N m, s, 1/s. Samples come with their time; a gap longer than ``max_gap``, a repeated
or an older time restarts the observer at that sample (r = 0; ``restarted`` says why).
"""

from __future__ import annotations

import math

import numpy as np

from irb140_dynamics.core.algorithms.momentum import energy_gradient, kinetic_energy, momentum_terms  # noqa: F401 (part of this module's interface)
from irb140_dynamics.core.codegen.kernels import VERBS_KERNELS, kernels_of
from irb140_dynamics.core.dynamics import gravity
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.model.states import finite_result, state

_KEPT = VERBS_KERNELS.kept  # id(model) -> its kernels: read inline on the hot path, else kernels_of


def monitor_terms(model: RobotModel, q, qd, qdd) -> tuple[list, list, list, list]:
    """(tau, g, p, beta) of one sample, in one pass over the arm (lists of floats): tau =
    rnea(q, qd, qdd) and g = gravity(q), checked finite (else ValueError, as rnea's), and
    the observer's p = M qd and beta = C^T qd - g - tau_f (see MomentumObserver.advance).
    What a node that monitors the arm needs per sample, at about the cost of one rnea: run
    as C once the kernel is native (see dynamics.rnea) and the states are float64 arrays."""
    n = model.n
    kernel = (_KEPT.get(id(model)) or kernels_of(model)).monitor
    found = None if kernel.native is None else kernel.native(q, qd, qdd)  # None unless (n,) float64, finite
    if found is not None:
        terms, qd = found.tolist(), qd.tolist()
    else:
        kernel.used()
        q, qd, qdd = state(q, n, "q"), state(qd, n, "qd"), state(qdd, n, "qdd")
        terms = kernel.scalar(q, qd, qdd)
    tau, g, p, c = list(terms[:n]), list(terms[n : 2 * n]), list(terms[2 * n : 3 * n]), terms[3 * n :]
    if not math.isfinite(sum(tau) + sum(g)):
        finite_result(tau, "rnea", q=q, qd=qd, qdd=qdd)
        finite_result(g, "gravity", q=q)
    friction = None if model.friction is None else model.friction.listed(qd)
    if friction is not None:
        tau = [t + f for t, f in zip(tau, friction)]
    return tau, g, p, _beta(c, g, friction)


def _beta(c, g, friction) -> list:
    """C^T qd - g - tau_f (friction None: none), what the observer integrates besides tau and r."""
    beta = [ci - gi for ci, gi in zip(c, g)]
    return beta if friction is None else [b - f for b, f in zip(beta, friction)]


def _restart_kind(dt: float) -> str:
    """Why a time step dt [s] restarts the observer."""
    return "repeated_stamp" if dt == 0.0 else "older_stamp" if dt < 0.0 else "gap"


class MomentumObserver:
    """The residual r ~ tau_ext [N m], updated sample by sample."""

    def __init__(self, model: RobotModel, gain: float, max_gap: float = 0.1):
        if not gain > 0.0:
            raise ValueError(f"gain: must be > 0 1/s, got {gain}")
        self.model, self.gain, self.max_gap = model, float(gain), float(max_gap)
        self.reset()

    def reset(self) -> None:
        """Forget the past: the next sample starts the observer again."""
        self._r = [0.0] * self.model.n
        self._t = None
        self.restarted: str | None = None  # why the last sample restarted the observer (see advance)

    @property
    def r(self) -> np.ndarray:
        """The residual after the last sample [N m]."""
        return np.array(self._r)

    def update(self, t: float, q, qd, tau, g=None) -> np.ndarray:
        """The residual after the sample (t [s], q, qd, tau measured): r, or zeros after a reset.

        ``g``: gravity(model, q) if the caller has it already. ValueError (and a reset) if a
        value is not finite.
        """
        return np.array(self.advance(t, q, qd, tau, g))

    def advance(self, t: float, q, qd, tau, g=None, terms=None) -> list[float]:
        """``update``, the residual as a list. Plain Python arithmetic on n floats: a few
        microseconds besides the kernel, where small NumPy arrays would cost tens.
        ``terms``: (p, beta) of monitor_terms at (q, qd), if the caller has them already.
        ``restarted`` is then "gap", "repeated_stamp" or "older_stamp" if the sample's time
        restarted the observer (r = 0), None if not or if it is the first since a reset."""
        n = self.model.n
        tau = state(tau, n, "tau")
        if terms is None:
            p, beta = self._momentum_terms(state(q, n, "q"), state(qd, n, "qd"), g)
        else:
            p, beta = terms
        drive = [x + y for x, y in zip(tau, beta)]
        if self._t is None or not 0.0 < t - self._t <= self.max_gap:
            self.restarted = None if self._t is None else _restart_kind(t - self._t)
            self._r = [0.0] * n
            self._t, self._p0, self._integral, self._drive = t, p, [0.0] * n, drive
            return self._r
        dt, K = t - self._t, self.gain
        # the drive by the trapezoid rule, r implicitly (backward Euler: r_k in the step to
        # t_k): r_k = K (p_k - p_0 - I_k), I_k = I_{k-1} + dt (drive) + dt r_k, so r_k is
        # K (p_k - p_0 - I_{k-1} - dt drive) / (1 + K dt), stable for any K dt (the
        # explicit step, with r_{k-1}, diverges beyond K dt = 2: K 2000 1/s at 1 kHz)
        partial_sum = [
            i + 0.5 * (d + d0) * dt  # Python floats: an overflow is inf, checked below
            for i, d, d0 in zip(self._integral, drive, self._drive)
        ]
        r = [K * (x - x0 - i) / (1.0 + K * dt) for x, x0, i in zip(p, self._p0, partial_sum)]
        integral = [i + ri * dt for i, ri in zip(partial_sum, r)]
        if not math.isfinite(sum(r)) and not all(map(math.isfinite, r)):
            self.reset()
            raise ValueError(f"observer residual not finite: {r}")
        self._t, self._integral, self._drive, self._r = t, integral, drive, r
        self.restarted = None
        return r

    def _momentum_terms(self, q, qd, g=None) -> tuple[list, list]:
        """p = M qd and C^T qd - g - tau_f: what the observer integrates besides tau and r."""
        model = self.model
        terms = kernels_of(model).momentum.scalar(q, qd)
        n = model.n
        g = gravity(model, q) if g is None else g
        friction = None if model.friction is None else model.friction.listed(qd)
        return list(terms[:n]), _beta(terms[n:], g.tolist() if type(g) is np.ndarray else g, friction)
