"""The generalized momentum p = M(q) qd and dT/dq = C(q, qd)^T qd on scalars, O(n), for the
momentum observer (``core.monitoring.observer``); ``energy_gradient`` is their definition.
"""

from __future__ import annotations

from irb140_dynamics.core.algorithms.recursions import (
    add,
    cross,
    dot,
    gather,
    inertia_times,
    parents,
    scale,
    steps,
    to_child,
    to_parent_wrench,
)
from irb140_dynamics.core.model.rigid_body import ZERO3
from irb140_dynamics.core.scalars.dual import dual_angles, partial


def kinetic_energy(links, cs, qd):
    """T = sum over links of 1/2 m v.v + v.(w x h) + 1/2 w.(I w), v the velocity of o_i."""
    parent, velocities = parents(links), []
    energy = 0.0
    for i, (link, (rot, p0), qd_i) in enumerate(zip(links, steps(links, cs), qd)):
        w, v = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)) if parent[i] < 0 else velocities[parent[i]]
        v = _joint_velocity(link, p0, w, v, qd_i)
        w = to_child(link, rot, w) if link.prismatic else add(to_child(link, rot, w), scale(qd_i, link.b))
        v = add(to_child(link, rot, v), cross(w, link.p))
        velocities.append((w, v))
        energy = energy + 0.5 * (link.m * dot(v, v) + dot(w, inertia_times(link.I, w))) + dot(v, cross(w, link.h))
    return energy


def _joint_velocity(link, p0, w, v, qd_i):
    """The velocity of the joint origin o'_i in frame i-1, from o_{i-1}'s v and w."""
    if p0 is not None:
        v = add(v, cross(w, p0))
    return add(v, scale(qd_i, link.e)) if link.prismatic else v


def energy_gradient(links, cs, qd):
    """dT/dq = C(q, qd)^T qd, exact: T on dual numbers carrying d/dq_k."""
    T = kinetic_energy(links, dual_angles(cs), qd)
    return [partial(T, k) for k in range(len(links))]


def momentum_terms(links, cs, qd):
    """[p, dT/dq]: the generalized momentum M qd and C^T qd, O(n).

    With h_i the spatial momentum of link i, H_k the sum over the subtree of link k (k and its descendants) and v_k the
    spatial velocity of link k: turning joint k at fixed qd turns the subtree about S_k,
    dv_i/dq_k = S_k x (v_i - v_k) and dI_i/dq_k = S_k x* I_i - I_i S_k x, which leaves
    (Featherstone's notation, x* the force cross product)

        p_k = S_k . H_k,    dT/dq_k = -S_k . (v_k x* H_k).

    Forward: each link's velocity (w; u at the joint origin o'_i, v at o_i). Backward: H
    (linear L, angular A about o'_k) gathered like RNEA's wrenches; S_k . (v_k x* H_k) is
    b . (w x A + u x L); for a prismatic joint (S_k = (0, b)) p_k = b . L and
    S_k . (v_k x* H_k) = b . (w x L).
    """
    moves = steps(links, cs)
    parent = parents(links)
    frames = []
    for i, (link, (rot, p0), qd_i) in enumerate(zip(links, moves, qd)):  # velocities, as forward_motion's
        w, _, v = (ZERO3, ZERO3, ZERO3) if parent[i] < 0 else frames[parent[i]]
        v = _joint_velocity(link, p0, w, v, qd_i)
        w = to_child(link, rot, w) if link.prismatic else add(to_child(link, rot, w), scale(qd_i, link.b))
        u = to_child(link, rot, v)  # the joint origin's velocity, in frame i
        v = add(u, cross(w, link.p))
        frames.append((w, u, v))
    n_links = len(links)
    p, gradient = [0.0] * n_links, [0.0] * n_links
    carried = [None] * n_links  # the children's subtrees' momentum, about o_i in frame i
    for i in reversed(range(n_links)):
        link, (w, u, v) = links[i], frames[i]
        L, A = carried[i] or (ZERO3, ZERO3)
        L_i = add(scale(link.m, v), cross(w, link.h))
        L = add(L, L_i)
        A = add(A, inertia_times(link.I, w), cross(link.h, v), cross(link.p, L))  # about o'_i
        if link.prismatic:
            p[i] = dot(link.b, L) + link.armature * qd[i]
            gradient[i] = -dot(link.b, cross(w, L))
        else:
            p[i] = dot(link.b, A) + link.armature * qd[i]
            gradient[i] = -dot(link.b, add(cross(w, A), cross(u, L)))
        if parent[i] >= 0:
            gather(carried, parent[i], to_parent_wrench(link, moves[i], L, A))
    return p + gradient
