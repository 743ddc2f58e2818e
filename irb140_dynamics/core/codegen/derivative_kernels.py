"""The recipes of the derivative kernels (see ``kernels.RECIPES``): the derivatives of the
dynamics in closed form (``algorithms.analytical_derivatives``: a chain's in the frame of
one of its first links, a tree's each subtree on the base in its first link's; with mimic
joints rnea on dual numbers through the coordinates), the forward dynamics and M^-1
(``algorithms.derivatives``, ``algorithms.linear``) on an arm's links.

Each is ``recipe(arm, cs, *groups, k, friction)`` with ``arm`` an ``ArmKernels``. The joint
friction is part of these kernels: its coefficients follow, in ``k``, the inputs of the payload's
and gravity's numbers (``kernels.inputs_of``): viscous v (n), then, with ``friction`` "coulomb", the
Coulomb levels c (n) and the smoothing velocity v_s, as ``Kernels`` binds them; ``friction``
None: none. Matrices are written row by row.
"""

from __future__ import annotations

from irb140_dynamics.core.algorithms import analytical_derivatives as analytical
from irb140_dynamics.core.algorithms import derivatives
from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.algorithms.linear import factors, inverse, negated, times, times_vector
from irb140_dynamics.core.algorithms.topology import is_chain
from irb140_dynamics.core.codegen.trace import size, tanh
from irb140_dynamics.core.scalars.dual import Dual

REFERENCES = 2  # frames tried for the analytical derivatives: links 0 and 1 (see _shortest)


def friction_terms(arm, k, qd, kind: str | None):
    """(torques, slopes d tau_f,i / d qd_i) of the joint friction at qd, as ``JointFriction``
    computes the torques (tau_f,i = v_i qd_i + c_i tanh(qd_i / v_s)); None without friction."""
    if kind is None:
        return None
    start, n = arm.inputs, arm.n
    viscous = k[start : start + n]
    if kind == "viscous":
        return [v * x for v, x in zip(viscous, qd)], list(viscous)
    coulomb, s = k[start + n : start + 2 * n], k[start + 2 * n]
    shapes = [tanh(x / s) for x in qd]
    torques = [v * x + c * t for v, c, x, t in zip(viscous, coulomb, qd, shapes)]
    return torques, [v + c * (1.0 - t * t) / s for v, c, t in zip(viscous, coulomb, shapes)]


def _references(arm) -> range:
    """The frames the analytical derivatives are tried in (see ``_shortest``): a chain's
    first REFERENCES links', a tree's -1 (each subtree on the base in its first link's)."""
    return range(min(REFERENCES, arm.n)) if is_chain(arm.links) else range(-1, 0)


def _coordinate_partials(arm, links, cs, qd, qdd, gravity, slopes=None):
    """(d tau / dq, d tau / dqd) of the coordinates of an arm with mimic joints: rnea on
    dual numbers carrying d/dq_k and d/dqd_k, every link's from its coordinate's."""
    n = arm.n
    zeros = (0.0,) * (2 * n)
    velocities = [Dual(v, zeros[: n + k] + (1.0,) + zeros[n + k + 1 :]) for k, v in enumerate(qd)]
    angles, velocities, accelerations = arm.expanded(arm.dual_angles(cs, 2 * n), velocities, qdd)
    tau = arm.projected(algorithms.rnea(links, angles, velocities, accelerations, gravity))
    parts = [t.d if isinstance(t, Dual) else zeros for t in tau]
    dq, dqd = [list(p[:n]) for p in parts], [list(p[n:]) for p in parts]
    for i, slope in enumerate(slopes or ()):
        dqd[i][i] = dqd[i][i] + slope
    return dq, dqd


def _coordinate_forward(arm, links, cs, qd, tau, gravity, friction_torques=None):
    """(qdd, M, M^-1) of the coordinates of an arm with mimic joints."""
    angles, velocities = arm.expanded(cs, qd)
    M = arm.projected_matrix(algorithms.crba(links, angles))
    bias = arm.projected(algorithms.rnea(links, angles, velocities, [0.0] * arm.n_links, gravity))
    if friction_torques is not None:
        bias = [b + f for b, f in zip(bias, friction_torques)]
    Minv = inverse(M)
    return times_vector(Minv, [t - b for t, b in zip(tau, bias)]), M, Minv


def _forward(arm, links, cs, qd, tau, gravity, friction_torques):
    if arm.coupled is not None:
        return _coordinate_forward(arm, links, cs, qd, tau, gravity, friction_torques)
    return derivatives.forward_dynamics(links, cs, qd, tau, gravity, friction_torques)


def _mass_matrix(arm, links, cs):
    (angles,) = arm.expanded(cs)
    return arm.projected_matrix(algorithms.crba(links, angles))


def _flat(*matrices) -> list:
    return [x for matrix in matrices for row in matrix for x in row]


def rnea_derivatives(arm, cs, qd, qdd, k, friction=None):
    """[d tau / dq, d tau / dqd, M]."""
    links, terms = arm.links_with(k), friction_terms(arm, k, qd, friction)
    if arm.coupled is not None:
        dq, dqd = _coordinate_partials(arm, links, cs, qd, qdd, arm.gravity_of(k), terms and terms[1])
        return _flat(dq, dqd, _mass_matrix(arm, links, cs))
    return _shortest(
        lambda r: analytical.rnea_partials(links, cs, qd, qdd, arm.gravity_of(k), terms and terms[1], r),
        _references(arm),
    )


def forward_dynamics(arm, cs, qd, tau, k, friction=None):
    """qdd = M^-1 (tau - b(q, qd)), friction in b."""
    terms = friction_terms(arm, k, qd, friction)
    return _forward(arm, arm.links_with(k), cs, qd, tau, arm.gravity_of(k), terms and terms[0])[0]


def forward_dynamics_derivatives(arm, cs, qd, tau, k, friction=None):
    """[d qdd / dq, d qdd / dqd, M^-1]: with mimic joints -M^-1 d tau / d(q, qd) at qdd = FD(q, qd, tau)."""
    links, terms = arm.links_with(k), friction_terms(arm, k, qd, friction)
    # M singular for every q is refused (SingularMatrix) as inverse_mass_matrix refuses it: in
    # the joint frames a joint moving no inertia leaves a pivot of folded zero, where in link
    # r's frame its M may keep a rounding residue (a pivot of 1e-17, M^-1 of 1e16)
    factors(_mass_matrix(arm, links, cs))
    if arm.coupled is not None:
        gravity = arm.gravity_of(k)
        qdd, _, Minv = _coordinate_forward(arm, links, cs, qd, tau, gravity, terms and terms[0])
        dq, dqd = _coordinate_partials(arm, links, cs, qd, qdd, gravity, terms and terms[1])
        minus = negated(Minv)
        return _flat(times(minus, dq), times(minus, dqd), Minv)
    return _shortest(
        lambda r: analytical.forward_dynamics_partials(links, cs, qd, tau, arm.gravity_of(k), terms, r),
        _references(arm),
    )


def inverse_mass_matrix(arm, cs, k):
    """The upper triangle of M^-1, row by row."""
    Minv = inverse(_mass_matrix(arm, arm.links_with(k), cs))
    return [Minv[i][j] for i in range(arm.n) for j in range(i, arm.n)]


def _shortest(matrices_in, references: range) -> list:
    """The matrices (flat, row by row) of ``matrices_in(r)`` computed in the frame of link r,
    for the r of ``references`` whose traced code is the shortest: which one is depends on
    where the arm's geometry has its zeros."""
    candidates = [[x for matrix in matrices_in(r) for row in matrix for x in row] for r in references]
    return min(candidates, key=size)
