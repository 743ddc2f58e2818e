"""The rigid-body parameter regressor on scalars: tau = Y(q, qd, qdd) pi, written like ``rnea``.

Y is n x 10n: column 10 k + j is the torque of link k's j-th inertial parameter, in
Pinocchio's order and frame (see ``core.regressor``, which generates code from this).
"""

from __future__ import annotations

from irb140_dynamics.core.algorithms.recursions import (
    Link,
    add,
    ancestors,
    cross,
    dot,
    forward_motion,
    inertia_times,
    rotate,
    steps,
    swept,
)

INERTIAL_PARAMETERS = 10  # per link: m, the first moment m c (3), the inertia's 6 entries

# Pinocchio's inertia order as entries (xx, yy, zz, xy, xz, yz) of our inertia 6-tuples
_UNIT_INERTIAS = tuple(tuple(1.0 if k == position else 0.0 for k in range(6)) for position in (0, 3, 1, 4, 5, 2))
_UNIT_VECTORS = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def rigid_body_regressor(links, cs, qd, qdd, gravity):
    """The n x 10n rigid-body regressor (rows of columns), written on scalars like ``rnea``."""
    moves = steps(links, cs)
    motion = forward_motion(links, moves, qd, qdd, gravity, at_joints=True)
    n = len(links)
    Y = [[0.0] * (INERTIAL_PARAMETERS * n) for _ in range(n)]
    for k in range(n):
        w, dw, a = _in_joint_frame(links[k], *motion[k])
        for column, (f, moment) in enumerate(_unit_wrenches(w, dw, a)):
            Y[k][INERTIAL_PARAMETERS * k + column] = dot(links[k].u, f if links[k].prismatic else moment)
            child = k
            for i in ancestors(links, k):  # only they carry link k's wrench
                f, moment = _to_parent_joint_frame(links[child], moves[child], links[i], f, moment)
                Y[i][INERTIAL_PARAMETERS * k + column] = dot(links[i].u, f if links[i].prismatic else moment)
                child = i
    return Y


def _in_joint_frame(link: Link, w, dw, a):
    """Link motion (a at the joint origin o'_i) in frame i, in the joint frame."""
    if link.R1 is None:
        return w, dw, a
    return rotate(link.R1, w), rotate(link.R1, dw), rotate(link.R1, a)


def _unit_wrenches(w, dw, a):
    """The wrench (about the joint origin) that each unit inertial parameter needs."""
    yield a, (0.0, 0.0, 0.0)  # m
    for e in _UNIT_VECTORS:  # m c
        yield swept(w, dw, e), cross(e, a)
    for E in _UNIT_INERTIAS:
        yield (0.0, 0.0, 0.0), add(inertia_times(E, dw), cross(w, inertia_times(E, w)))


def _to_parent_joint_frame(child: Link, move, parent: Link, f, n):
    """A wrench about o'_child in its joint frame, as one about o'_parent in the parent's."""
    rot, p0 = move
    if rot is not None:
        f, n = rotate(rot, f), rotate(rot, n)
    if child.R0 is not None:
        f, n = rotate(child.R0, f), rotate(child.R0, n)
    if p0 is not None:
        n = add(n, cross(p0, f))
    n = add(n, cross(parent.p, f))  # about o'_parent, parent link frame
    if parent.R1 is not None:
        f, n = rotate(parent.R1, f), rotate(parent.R1, n)
    return f, n
