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

from irb140_dynamics.core.algorithms.recursions import add, cross, dot, inertia_times, scale, to_child, to_parent_wrench, turns
from irb140_dynamics.core.scalars.dual import dual_angles, partial
from irb140_dynamics.core.dynamics import gravity
from irb140_dynamics.core.model.states import finite_result, state
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.model.rigid_body import ZERO3


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


def momentum_terms(links, cs, qd):
    """[p, dT/dq]: the generalized momentum M qd and C^T qd, O(n).

    With h_i the spatial momentum of link i, H_k the sum over the subtree k..n and v_k the
    spatial velocity of link k: turning joint k at fixed qd turns the subtree about S_k,
    dv_i/dq_k = S_k x (v_i - v_k) and dI_i/dq_k = S_k x* I_i - I_i S_k x, which leaves
    (Featherstone's notation, x* the force cross product)

        p_k = S_k . H_k,    dT/dq_k = -S_k . (v_k x* H_k).

    Forward: each link's velocity (w; u at the joint origin o'_i, v at o_i). Backward: H
    (linear L, angular A about o'_k) gathered like RNEA's wrenches; S_k . (v_k x* H_k) is
    b . (w x A + u x L).
    """
    rots = turns(links, cs)
    w, v = ZERO3, ZERO3
    frames = []
    for link, rot, qd_i in zip(links, rots, qd):  # velocities, as forward_motion's
        if link.p0 is not None:
            v = add(v, cross(w, link.p0))
        w = add(to_child(link, rot, w), scale(qd_i, link.b))
        u = to_child(link, rot, v)  # the joint origin's velocity, in frame i
        v = add(u, cross(w, link.p))
        frames.append((w, u, v))
    n_links = len(links)
    p, gradient = [0.0] * n_links, [0.0] * n_links
    L, A = ZERO3, ZERO3  # the subtree's momentum
    for i in reversed(range(n_links)):
        link, (w, u, v) = links[i], frames[i]
        if i + 1 < n_links:
            L, A = to_parent_wrench(links[i + 1], rots[i + 1], L, A)
        L_i = add(scale(link.m, v), cross(w, link.h))
        L = add(L, L_i)
        A = add(A, inertia_times(link.I, w), cross(link.h, v), cross(link.p, L))  # about o'_i
        p[i] = dot(link.b, A) + link.armature * qd[i]
        gradient[i] = -dot(link.b, add(cross(w, A), cross(u, L)))
    return p + gradient


def monitor_terms(model: RobotModel, q, qd, qdd) -> tuple[list, list, list, list]:
    """(tau, g, p, beta) of one sample, in one pass over the arm (lists of floats): tau =
    rnea(q, qd, qdd) and g = gravity(q), checked finite (else ValueError, as rnea's), and
    the observer's p = M qd and beta = C^T qd - g - tau_f (see MomentumObserver.advance).
    What a node that monitors the arm needs per sample, at about the cost of one rnea."""
    n = model.n
    q, qd, qdd = state(q, n, "q"), state(qd, n, "qd"), state(qdd, n, "qdd")
    terms = model.kernels.monitor.scalar(q, qd, qdd)
    tau, g, p, c = list(terms[:n]), list(terms[n:2 * n]), list(terms[2 * n:3 * n]), terms[3 * n:]
    if not math.isfinite(sum(tau) + sum(g)):
        finite_result(tau, "rnea", q=q, qd=qd, qdd=qdd)
        finite_result(g, "gravity", q=q)
    friction = None if model.friction is None else model.friction.torques(qd).tolist()
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
        partial_sum = [i + 0.5 * (d + d0) * dt  # Python floats: an overflow is inf, checked below
                       for i, d, d0 in zip(self._integral, drive, self._drive)]
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
        terms = model.kernels.momentum.scalar(q, qd)
        n = model.n
        g = gravity(model, q) if g is None else g
        friction = None if model.friction is None else model.friction.torques(qd).tolist()
        return list(terms[:n]), _beta(terms[n:], g.tolist() if type(g) is np.ndarray else g, friction)
