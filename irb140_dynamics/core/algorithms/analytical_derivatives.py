"""d tau / dq, d tau / dqd and M in closed form, after Carpentier and Mansard (2018).

Spatial vectors in one frame, about its origin (the base's, or any link's: the scalar
products below do not depend on it; see ``_bodies``): a motion (w, v), a force (n, f), each
a pair of 3-vectors. Joint k's axis S_k (revolute: (z, o' x z), o' its origin; prismatic:
(0, z)); body i's velocity v_i = sum_{k <= i} S_k qd_k and acceleration a_i (gravity as the
base's acceleration), its force f_i = I_i a_i + v_i x* I_i v_i and tau_j = S_j . F_j,
F_j = sum_{i >= j} f_i. Moving q_k moves the bodies i >= k by S_k x; v_{k-1}, a_{k-1} stay.
With psid_k = v_{k-1} x S_k and psidd_k = a_{k-1} x S_k + v_{k-1} x psid_k:

    d f_i / dq_k  = S_k x* f_i + I_i psidd_k + B_i psid_k           (i >= k)
    d f_i / dqd_k = 2 I_i psid_k + B_i S_k                            (i >= k)

B_i x = v_i x* (I_i x) + I_i (x x v_i) + x x* (I_i v_i), whose matrix is [[T_i, 0],
[-2 [l_i]x, 0]] (it reads x's angular part only): T_i = [w]x Ibar - Ibar [w]x - ([u]x [h]x
+ [h]x [u]x) - [k_i]x, for v_i = (w, u), (Ibar, h, m) the body's inertia about the origin
and (k_i, l_i) = I_i v_i its momentum. Summed over the subtree (Y_j, BC_j composite):

    d tau_j / dq_k  = S_j . (Y_j psidd_k + BC_j psid_k)        k <= j
                    = S_j . (S_k x* F_k + Y_k psidd_k + BC_k psid_k)   k > j
    d tau_j / dqd_k = S_j . (2 Y_j psid_k + BC_j S_k)          k <= j
                    = S_j . (2 Y_k psid_k + BC_k S_k)           k > j
    M_jk = S_j . Y_k S_k                                       j <= k

(for k <= j, d S_j / dq_k = S_k x S_j cancels the S_k x* F_j of F_j's derivative).

On a tree "k <= j" reads "k is j or one of its ancestors", "k > j" "k is in j's subtree",
k - 1 is k's parent, and tau_j does not depend on a joint k that is neither j's ancestor
nor in its subtree; the composites sum over subtrees. A tree's derivatives are computed
with each subtree on the base in the frame of its first link (``reference`` -1).
"""

from __future__ import annotations

from irb140_dynamics.core.algorithms.linear import inverse, negated, times, times_vector
from irb140_dynamics.core.algorithms.recursions import add, cross, dot, rotate, scale, steps, to_child, turned
from irb140_dynamics.core.algorithms.topology import is_chain, lineages, parents
from irb140_dynamics.core.model.rigid_body import ZERO3, shift_inertia

IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def _matmul(A, B):
    return tuple(tuple(rotate(A, column)) for column in zip(*B))


def _product(A, B):
    """A B (rows)."""
    return tuple(zip(*_matmul(A, B)))


def _mcross(x, y):
    """motion x motion."""
    return cross(x[0], y[0]), add(cross(x[0], y[1]), cross(x[1], y[0]))


def _fcross(x, f):
    """motion x* force."""
    return add(cross(x[0], f[0]), cross(x[1], f[1])), cross(x[0], f[1])


def _add(*xs):
    return add(*(x[0] for x in xs)), add(*(x[1] for x in xs))


def _scale(k, x):
    return scale(k, x[0]), scale(k, x[1])


def _dot(x, y):
    return dot(x[0], y[0]) + dot(x[1], y[1])


def _symmetric_times(S, x):
    xx, yy, zz, xy, xz, yz = S
    return (xx * x[0] + xy * x[1] + xz * x[2], xy * x[0] + yy * x[1] + yz * x[2], xz * x[0] + yz * x[1] + zz * x[2])


def _inertia_times(inertia, x):
    """A rigid inertia (m, h, Ibar) about the origin times a motion: (Ibar w + h x v, m v - h x w)."""
    m, h, Ibar = inertia
    return add(_symmetric_times(Ibar, x[0]), cross(h, x[1])), add(scale(m, x[1]), cross(x[0], h))


def _bodies(links, cs, gravity, r: int):
    """(per link: its joint's axis S and its inertia (m, h, Ibar) about the origin; {each
    link on the base: gravity}), a chain's all in the frame of link ``r``; with ``r`` -1 (a
    tree) each subtree on the base in the frame of its first link (the derivatives relate a
    link only to its ancestors and its subtree). The scalar products the derivatives are
    made of do not depend on the frame; the links near the reference have few rotations
    between them and it, so their quantities have few terms."""
    moves, parent = steps(links, cs), parents(links)
    placements, axes = [None] * len(links), [None] * len(links)
    if r >= 0:
        for link, (rot, _) in zip(links[: r + 1], moves[: r + 1]):
            gravity = to_child(link, rot, gravity)
        placements[r], gravities = (IDENTITY, ZERO3), {0: gravity}
    else:
        gravities = {i: to_child(links[i], moves[i][0], gravity) for i, p in enumerate(parent) if p < 0}
        for i in gravities:
            placements[i] = IDENTITY, ZERO3
    for i in range(r + 1, len(links)):  # R_i = R_parent L_i, o_i = o_parent + R_parent p0 + R_i p
        if placements[i] is not None:  # a tree's link on the base
            continue
        R, o = placements[parent[i]]
        (rot, p0), link = moves[i], links[i]
        joint_origin = o if p0 is None else add(o, rotate(R, p0))
        z = rotate(R if link.R0 is None else _product(R, link.R0), link.u)  # before Rot: fewer terms
        axes[i] = (ZERO3, z) if link.prismatic else (z, cross(joint_origin, z))
        R = _local(R, link, rot)
        placements[i] = R, add(joint_origin, rotate(R, link.p))
    for i in reversed(range(r)):  # (a chain) R_i = R_{i+1} L_{i+1}^T, o_i = o_{i+1} - R_{i+1} p - R_i p0
        R, o = placements[i + 1]
        (rot, p0), link = moves[i + 1], links[i + 1]
        o = add(o, scale(-1.0, rotate(R, link.p)))
        R = _local_back(R, link, rot)
        placements[i] = R, o if p0 is None else add(o, scale(-1.0, rotate(R, p0)))
    out = []
    for link, (R, o), S in zip(links, placements, axes):
        if S is None:  # from the link's own frame
            z = rotate(R, link.b)
            joint_origin = add(o, scale(-1.0, rotate(R, link.p)))
            S = (ZERO3, z) if link.prismatic else (z, cross(joint_origin, z))
        out.append((S, shift_inertia(link.m, rotate(R, link.h), turned(R, link.I), o)))
    return out, gravities


def _local(R, link, rot):
    """R L with L = R0 Rot R1, link i's rotation in frame i-1 (rot None: identity)."""
    for factor in (link.R0, rot, link.R1):
        if factor is not None:
            R = _product(R, factor)
    return R


def _local_back(R, link, rot):
    """R L^T."""
    for factor in (link.R1, rot, link.R0):
        if factor is not None:
            R = _product(R, tuple(zip(*factor)))
    return R


def _motion(bodies, parent, qd, qdd, gravities):
    """The forward pass: per link psid, psidd, and its body's (momentum, force, Coriolis
    block); qdd None: zero. ``gravities``: see _bodies."""
    psid, psidd, parts, motion = [], [], [], []
    for i, ((S, inertia), qd_i) in enumerate(zip(bodies, qd)):
        v, a = ((ZERO3, ZERO3), (ZERO3, scale(-1.0, gravities[i]))) if parent[i] < 0 else motion[parent[i]]
        psid.append(_mcross(v, S))
        psidd.append(_add(_mcross(a, S), _mcross(v, psid[-1])))
        v = _add(v, _scale(qd_i, S))
        a = _add(a, _scale(qd_i, psid[-1])) if qdd is None else _add(a, _scale(qdd[i], S), _scale(qd_i, psid[-1]))
        motion.append((v, a))
        momentum = _inertia_times(inertia, v)
        force = _add(_inertia_times(inertia, a), _fcross(v, momentum))
        parts.append((momentum, force, _coriolis_block(inertia, v, momentum)))
    return psid, psidd, parts


def _subtree_sums(own, parent, plus):
    """Each link's ``own`` summed over its subtree, its own term first (a chain's: own_k
    plus the next link's sum)."""
    total = list(own)
    for k in reversed(range(len(own))):
        if parent[k] >= 0:
            p = parent[k]
            total[p] = plus(total[p], total[k])
    return total


def _composite_inertias(bodies, armature, parent, lineage):
    """(Y_k, alpha_k = Y_k S_k per link, M)."""
    n = len(bodies)
    Y = _subtree_sums([body[1] for body in bodies], parent, _sum_inertia)
    alpha = [_inertia_times(Y[k], bodies[k][0]) for k in range(n)]
    M = [[0.0] * n for _ in range(n)]
    for j in range(n):
        for k in range(j, n):
            if j in lineage[k]:
                M[j][k] = M[k][j] = _dot(bodies[j][0], alpha[k])
        M[j][j] = M[j][j] + armature[j]
    return Y, alpha, M


def _coriolis_block(inertia, v, momentum):
    """(the symmetric part of T (6 entries), k) of B for a body (see the module)."""
    m, h, Ibar = inertia
    w, u = v
    xx, yy, zz, xy, xz, yz = Ibar
    # P = [w]x Ibar; its symmetric part P + P^T
    rows = (
        (w[1] * xz - w[2] * xy, w[1] * yz - w[2] * yy, w[1] * zz - w[2] * yz),
        (w[2] * xx - w[0] * xz, w[2] * xy - w[0] * yz, w[2] * xz - w[0] * zz),
        (w[0] * xy - w[1] * xx, w[0] * yy - w[1] * xy, w[0] * yz - w[1] * xz),
    )
    uh = dot(u, h)
    return (
        (rows[0][0] - u[0] * h[0] + uh) * 2.0,
        (rows[1][1] - u[1] * h[1] + uh) * 2.0,
        (rows[2][2] - u[2] * h[2] + uh) * 2.0,
        rows[0][1] + rows[1][0] - (u[0] * h[1] + h[0] * u[1]),
        rows[0][2] + rows[2][0] - (u[0] * h[2] + h[0] * u[2]),
        rows[1][2] + rows[2][1] - (u[1] * h[2] + h[1] * u[2]),
    ), momentum[0]


def _sum_inertia(a, b):
    return a[0] + b[0], add(a[1], b[1]), tuple(x + y for x, y in zip(a[2], b[2]))


def rnea_partials(links, cs, qd, qdd, gravity, friction_slopes=None, reference: int | None = None):
    """(d tau / dq, d tau / dqd, M), each n rows of n (friction given by its slopes d tau_f,i /
    d qd_i; armature on M's diagonal), computed in the frame of link ``reference`` (see
    ``_reference``)."""
    reference, parent, lineage = _reference(links, reference), parents(links), lineages(links)
    first_turns = _turns_about_gravity(links, gravity, lineage)
    bodies, gravities = _bodies(links, cs, gravity, reference)
    Y, alpha, M = _composite_inertias(bodies, [link.armature for link in links], parent, lineage)
    motion = _motion(bodies, parent, qd, qdd, gravities)
    dq, dqd = _partials(bodies, parent, lineage, Y, alpha, *motion, friction_slopes, first_turns)
    return dq, dqd, M


def forward_dynamics_partials(links, cs, qd, tau, gravity, friction=None, reference: int | None = None):
    """(d qdd / dq, d qdd / dqd, M^-1) at qdd = FD(q, qd, tau); ``friction``: (torques,
    slopes) at qd, or None. The bias torques come from the same pass, at qdd = 0."""
    n, parent, lineage = len(links), parents(links), lineages(links)
    reference = _reference(links, reference)
    first_turns = _turns_about_gravity(links, gravity, lineage)
    bodies, gravities = _bodies(links, cs, gravity, reference)
    Y, alpha, M = _composite_inertias(bodies, [link.armature for link in links], parent, lineage)
    Minv = inverse(M)
    psid, psidd, parts = _motion(bodies, parent, qd, None, gravities)
    total = _subtree_sums([part[1] for part in parts], parent, _add)
    bias = [_dot(bodies[j][0], total[j]) for j in range(n)]
    if friction is not None:
        bias = [b + f for b, f in zip(bias, friction[0])]
    qdd = times_vector(Minv, [t - b for t, b in zip(tau, bias)])
    # with qdd: a_i gains A_i = sum_{l <= i} S_l qdd_l, psidd_k gains A_{k-1} x S_k, f_i gains I_i A_i
    A = [None] * n
    for i, ((S, inertia), part) in enumerate(zip(bodies, parts)):
        above = A[parent[i]] if parent[i] >= 0 else None
        if above is not None:
            psidd[i] = _add(psidd[i], _mcross(above, S))
        A[i] = _scale(qdd[i], S) if above is None else _add(above, _scale(qdd[i], S))
        parts[i] = (part[0], _add(part[1], _inertia_times(inertia, A[i])), part[2])
    slopes = friction and friction[1]
    dq, dqd = _partials(bodies, parent, lineage, Y, alpha, psid, psidd, parts, slopes, first_turns)
    negative = negated(Minv)  # once for both products
    return times(negative, dq), times(negative, dqd), Minv


def _reference(links, reference: int | None) -> int:
    """The frame of the computation: a chain's link ``reference`` (None: 0), a tree's -1
    (each subtree on the base in its first link's; ValueError for another)."""
    if is_chain(links):
        return 0 if reference is None else reference
    if reference not in (None, -1):
        raise ValueError(
            f"a tree's derivatives are computed with each subtree in its first link's frame (reference -1), not {reference}"
        )
    return -1


def _turns_about_gravity(links, gravity, lineage) -> bool:
    """Whether the first joint turns the whole arm (every link) about the direction of
    gravity (its axis and gravity parallel, as zeros of the traced constants show): then
    nothing depends on q_0, and d tau / dq_0 is zero, exactly."""
    first = links[0]
    if first.prismatic or not all(0 in line for line in lineage):
        return False
    axis = first.u if first.R0 is None else rotate(first.R0, first.u)
    return all(isinstance(c, float) and c == 0.0 for c in cross(gravity, axis))


def _composite(a, b):
    """The sum of two (momentum, force, (sym, spin)) of the forward pass."""
    (HA, FA, (SA, KA)), (HB, FB, (SB, KB)) = a, b
    return _add(HA, HB), _add(FA, FB), (tuple(x + y for x, y in zip(SA, SB)), add(KA, KB))


def _partials(bodies, parent, lineage, Y, alpha, psid, psidd, parts, friction_slopes, first_turns=False):
    """(d tau / dq, d tau / dqd) from the forward pass (see the module); ``first_turns``:
    d tau / dq_0 is zero (see _turns_about_gravity)."""
    n = len(bodies)
    beta, G, H = [None] * n, [None] * n, [None] * n
    twice = [_scale(2.0, x) for x in psid]  # 2 psid_k
    composites = _subtree_sums(parts, parent, _composite)
    for k in range(n):
        momentum, force, (sym, spin) = composites[k]
        twice_linear, S = scale(2.0, momentum[1]), bodies[k][0]

        def coriolis(x, sym=sym, spin=spin, twice_linear=twice_linear):  # BC_k x, x's angular part
            return add(_symmetric_times(sym, x), cross(x, spin)), cross(x, twice_linear)

        beta[k] = add(_symmetric_times(sym, S[0]), cross(spin, S[0]), cross(twice_linear, S[1]))
        G[k] = _add(_fcross(S, force), _inertia_times(Y[k], psidd[k]), coriolis(psid[k][0]))
        H[k] = _add(_inertia_times(Y[k], twice[k]), coriolis(S[0]))

    dq = [[None] * n for _ in range(n)]
    dqd = [[None] * n for _ in range(n)]
    for j in range(n):
        S = bodies[j][0]
        for k in range(n):
            if k == 0 and first_turns:
                dq[j][k], dqd[j][k] = 0.0, _dot(alpha[j], twice[k]) + dot(beta[j], bodies[k][0][0])
            elif k in lineage[j]:  # k is j or one of its ancestors
                dq[j][k] = _dot(alpha[j], psidd[k]) + dot(beta[j], psid[k][0])
                dqd[j][k] = _dot(alpha[j], twice[k]) + dot(beta[j], bodies[k][0][0])
            elif j in lineage[k]:  # k is in j's subtree
                dq[j][k], dqd[j][k] = _dot(S, G[k]), _dot(S, H[k])
            else:
                dq[j][k], dqd[j][k] = 0.0, 0.0
        if friction_slopes is not None:
            dqd[j][j] = dqd[j][j] + friction_slopes[j]
    return dq, dqd
