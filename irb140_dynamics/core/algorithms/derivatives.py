"""The derivatives of the dynamics by dual numbers, and the forward dynamics on scalars.

``rnea_partials`` is the definition: ``rnea`` of ``recursions`` run on dual numbers whose
parts are d/dq_k (from the joint angles' cos and sin, or a prismatic joint's slide) and
d/dqd_k (from the velocities), 2n parts in all: exact partial derivatives, with no
formula of their own. The kernels compute the same matrices in closed form
(``analytical_derivatives``, fewer operations), tested against this.

``forward_dynamics``: qdd = M^-1 (tau - b(q, qd)) with M by the composite rigid body
algorithm and M^-1 by M = L D L^T (``linear``), on any scalar type.

Joint friction (tau_f,i = v_i qd_i + c_i tanh(qd_i / v_s), see ``model.friction``) enters
as its torques or its slopes at the state, computed by the caller (whose number type may
not know tanh).
"""

from __future__ import annotations

from irb140_dynamics.core.algorithms.linear import inverse, times_vector
from irb140_dynamics.core.algorithms.recursions import crba, rnea
from irb140_dynamics.core.scalars.dual import Dual, dual_angles, partial


def seeded(cs, qd):
    """(cs, qd) as dual numbers with 2n parts: d/dq_k (parts 0..n-1), d/dqd_k (n..2n-1)."""
    n = len(cs)
    zeros = (0.0,) * (2 * n)

    def unit(k, value):
        return zeros[:k] + (value,) + zeros[k + 1 :]

    angles = [
        (Dual(x[0], unit(k, 1.0)),) if len(x) == 1 else (Dual(x[0], unit(k, -x[1])), Dual(x[1], unit(k, x[0])))
        for k, x in enumerate(cs)
    ]
    return angles, [Dual(v, unit(n + k, 1.0)) for k, v in enumerate(qd)]


def _parts(x, count: int) -> tuple:
    return x.d if isinstance(x, Dual) else (0.0,) * count


def rnea_partials(links, cs, qd, qdd, gravity, friction_slopes=None):
    """(d tau / dq, d tau / dqd), each n rows of n, of ``rnea`` (with friction, given its
    slopes d tau_f,i / d qd_i: friction does not depend on q)."""
    n = len(links)
    angles, velocities = seeded(cs, qd)
    tau = rnea(links, angles, velocities, qdd, gravity)
    parts = [_parts(t, 2 * n) for t in tau]
    dq = [list(p[:n]) for p in parts]
    dqd = [list(p[n:]) for p in parts]
    if friction_slopes is not None:
        for i, slope in enumerate(friction_slopes):
            dqd[i][i] = dqd[i][i] + slope
    return dq, dqd


def forward_dynamics(links, cs, qd, tau, gravity, friction_torques=None):
    """(qdd, M, M^-1): qdd = M^-1 (tau - b(q, qd)), b the torques at qdd = 0 (friction in)."""
    n = len(links)
    M = crba(links, cs)
    bias = rnea(links, cs, qd, [0.0] * n, gravity)
    if friction_torques is not None:
        bias = [b + f for b, f in zip(bias, friction_torques)]
    Minv = inverse(M)
    return times_vector(Minv, [t - b for t, b in zip(tau, bias)]), M, Minv


def christoffel_coriolis(links, cs, qd):
    """The Coriolis matrix C(q, qd) from the Christoffel symbols of M(q).

    C_ij = sum_k 1/2 (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) qd_k, so that C qd is the
    Coriolis/centrifugal torque and Mdot - 2C is skew-symmetric. The partial derivatives
    of M are exact: crba runs on dual numbers carrying d/dq of each scalar.
    """
    return christoffel(crba(links, dual_angles(cs)), qd)


def christoffel(M, qd):
    """C(q, qd) of M(q) given on dual numbers carrying d/dq (see christoffel_coriolis)."""
    n = len(M)
    dM = [[[partial(M[i][j], k) for k in range(n)] for j in range(n)] for i in range(n)]
    return [
        [sum(0.5 * (dM[i][j][k] + dM[i][k][j] - dM[j][k][i]) * qd[k] for k in range(n)) for j in range(n)]
        for i in range(n)
    ]
