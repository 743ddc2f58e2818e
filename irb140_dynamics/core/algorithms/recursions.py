"""The dynamics algorithms, written once on scalar components.

Notation follows the report (Luh-Walker-Paul recursive Newton-Euler), everything of link i
expressed in its own frame i. Joint i moves link i by T_i = pre Rot(u, theta_i) post (see
``joints``); its axis passes through the joint origin o'_i = o_{i-1} + p0 (in frame i-1).

    q, qd, qdd   joint positions, velocities, accelerations
    w, dw, a     angular velocity, angular acceleration, linear acceleration of origin o_i
    b            joint i's axis, in frame i
    p0           o_{i-1} -> o'_i, in frame i-1 (zero for DH rows)
    p            o'_i -> o_i, in frame i (for DH rows o_{i-1} -> o_i)
    m, h, I      link mass, first moment m*c, inertia about o_i
    f, n         force and moment (about o'_i) that link i-1 exerts on link i
    tau          joint torques, tau_i = b . n_i (+ armature_i qdd_i); prismatic: b . f_i

A prismatic joint i slides by d_i = q_i along its axis, e = R0 u in frame i-1: its joint
origin o'_i = o_{i-1} + p0 + d_i e moves with it (``steps``), with velocity qd_i e and
acceleration qdd_i e relative to frame i-1; its rotation Rot is the identity.

The links form a tree: link i's parent is ``Link.parent`` (-1 the base, None the link
before: a chain), parents before children, as spatial_v2's ``model.parent``; "frame i-1"
below is the parent's frame. A link's motion comes from its parent's; the backward passes
gather each link's children's wrenches into it.

Vectors are 3-tuples, rotations 3x3 tuples of rows. A scalar may be a float, a NumPy array
(many states at once) or a symbol of ``codegen`` (which turns these functions into
straight-line code). So only ``+ - *`` are used, the joint angles enter as (cos, sin) pairs
computed by the caller (a prismatic joint's as the 1-tuple (d,)), and products with the
constants 0 and +-1 are left out: for a DH row the generated code is the same as that of a
hand-written DH recursion.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from irb140_dynamics.core.algorithms.leaf import cheap_turn_axis, leaf_wrench
from irb140_dynamics.core.algorithms.rotations import (  # noqa: F401 (part of this module's interface)
    Rotation,
    combination,
    fused,
    rotate,
    rotate_back,
    turn,
    turned,
    turned_about,
)
from irb140_dynamics.core.algorithms.topology import ancestors, children, parents  # noqa: F401 (part of this module's interface)
from irb140_dynamics.core.algorithms.vectors import add, cross, dot, gyroscopic, inertia_times, scale, swept  # noqa: F401 (part of this module's interface)
from irb140_dynamics.core.model.joints import Z_AXIS, snap
from irb140_dynamics.core.model.rigid_body import ZERO3, Inertia6, Vector3, shift_inertia
from irb140_dynamics.core.scalars.dual import Dual  # noqa: F401 (part of this module's interface)


@dataclass(frozen=True)
class Link:
    """Constants of link i for the recursions."""

    theta_offset: float
    R0: Rotation | None  # pre rotation (None: identity)
    p0: Vector3 | None  # pre translation, in frame i-1 (None: zero)
    u: Vector3  # the axis in the joint frame
    R1: Rotation | None  # post rotation (None: identity)
    p: Vector3  # post translation, in frame i
    b: Vector3  # the axis in frame i
    m: float
    h: Vector3
    I: Inertia6
    armature: float = 0.0
    prismatic: bool = False
    e: Vector3 = ZERO3  # a prismatic joint's axis in frame i-1 (R0 u)
    parent: int | None = None  # the parent link's index, -1 the base; None: the link before (a chain)


def chain(model) -> tuple[Link, ...]:
    """The per-link constants of a RobotModel, one per moving joint, mimic joints included
    (payload merged into the last link); each link's ``parent`` is the model's, None where
    it is the link before (so that a chain's links, and slices of them, are a chain)."""
    return tuple(
        Link(
            *_joint_constants(joint),
            *body.about_origin(),
            joint.armature,
            *_slide(joint),
            parent=None if parent == i - 1 else parent,
        )
        for i, (joint, body, parent) in enumerate(zip(model.joints, model.bodies, model.parent))
    )


def _slide(joint) -> tuple:
    """(prismatic, e) of a Link."""
    if not joint.prismatic:
        return False, ZERO3
    return True, tuple(float(x) for x in snap(joint.pre.rotation() @ np.array(joint.axis)))


@lru_cache(maxsize=256)  # a model rebuilt with another payload recomputes no joint's
def _joint_constants(joint) -> tuple:
    """(theta_offset, R0, p0, u, R1, p, b) of a Link."""
    pre, post = joint.pre, joint.post
    R1 = post.rotation()
    return (
        joint.offset,
        None if pre.rpy == ZERO3 else _rows(pre.rotation()),
        None if pre.xyz == ZERO3 else pre.xyz,
        joint.turning_axis,
        None if post.rpy == ZERO3 else _rows(R1),
        tuple(R1.T @ np.array(post.xyz)) if post.rpy != ZERO3 else post.xyz,
        tuple(snap(R1.T @ np.array(joint.turning_axis))),
    )


def flange_wrench(model, f_ext, n_ext):
    """A wrench on the flange (force, moment about the flange origin, flange frame) as one
    on the last link (moment about its origin, in its frame)."""
    if model.flange.is_identity:
        return f_ext, n_ext
    R = _rows(model.flange.rotation())
    f = rotate(R, f_ext)
    return f, add(rotate(R, n_ext), cross(model.flange.xyz, f))


def _rows(R) -> Rotation:
    return tuple(tuple(float(x) for x in row) for row in R)


def to_child(link: Link, rot, v):
    """R_i^T v: a vector of frame i-1 expressed in frame i (R_i = R0 Rot R1, rot = Rot, None
    for a prismatic joint)."""
    if link.R0 is not None:
        v = rotate_back(link.R0, v)
    if rot is not None:
        v = rotate_back(rot, v)
    return v if link.R1 is None else rotate_back(link.R1, v)


def to_parent(link: Link, rot, v):
    """R_i v: a vector of frame i expressed in frame i-1."""
    if link.R1 is not None:
        v = rotate(link.R1, v)
    if rot is not None:
        v = rotate(rot, v)
    return v if link.R0 is None else rotate(link.R0, v)


def steps(links, cs):
    """(Rot, p0) of each joint at its position: Rot None for a prismatic joint, whose p0
    (o_{i-1} -> o'_i, frame i-1, None: zero) then carries its slide d e."""
    out = []
    for link, x in zip(links, cs):
        if link.prismatic:
            slide = scale(x[0], link.e)
            out.append((None, slide if link.p0 is None else add(link.p0, slide)))
        else:
            out.append((turn(link.u, *x), link.p0))
    return out


# -- algorithms ---------------------------------------------------------------------


def rnea(links, cs, qd, qdd, gravity, f_ext=ZERO3, n_ext=ZERO3, at: int = -1):
    """Joint torques tau(q, qd, qdd) by the recursive Newton-Euler algorithm.

    ``cs`` holds (cos, sin) of each joint angle theta_i = q_i + theta_offset_i.
    (f_ext, n_ext) is the wrench the environment exerts on the last link (link ``at``), in
    its frame, the moment taken about its origin (see ``flange_wrench``); tau balances it (a load pressing
    on the flange raises tau like a weight would). Friction is not included.
    """
    plain = steps(links, cs)
    links, moves = fused(links, cs, plain)
    motion = forward_motion(links, moves, qd, qdd, gravity)
    parent, below = parents(links), children(links)
    tau = [0.0] * len(links)
    # the wrench each link's children (the environment, for the last one) exert on it, about
    # its origin o_i in its frame; gathered as the backward pass reaches them
    carried = [None] * len(links)
    carried[at] = scale(-1.0, f_ext), scale(-1.0, n_ext)
    base = ZERO3, ZERO3, scale(-1.0, gravity)
    for i in reversed(range(len(links))):
        link = links[i]
        axis = None if below[i] or moves[i] is not plain[i] else cheap_turn_axis(link)
        if axis is not None:  # a leaf whose inertia turns cheaply: its wrench before its turn
            motion_i = motion[parent[i]] if parent[i] >= 0 else base
            f, n = leaf_wrench(link, moves[i], motion_i, qd[i], qdd[i], carried[i], axis)
            tau[i] = dot(link.u, n) + link.armature * qdd[i]
            if parent[i] >= 0:
                if link.R0 is not None:
                    f, n = rotate(link.R0, f), rotate(link.R0, n)
                if moves[i][1] is not None:
                    n = add(n, cross(moves[i][1], f))
                gather(carried, parent[i], (f, n))
            continue
        w, dw, a = motion[i]
        f, n = carried[i] or (ZERO3, ZERO3)
        force = add(swept(w, dw, link.h), scale(link.m, a))
        moment = add(inertia_times(link.I, dw), gyroscopic(link.I, w), cross(link.h, a))
        f = add(force, f)
        n = add(moment, cross(link.p, f), n)
        tau[i] = dot(link.b, f if link.prismatic else n) + link.armature * qdd[i]
        if parent[i] >= 0:
            gather(carried, parent[i], to_parent_wrench(link, moves[i], f, n))
    return tau


def gather(carried, i, wrench) -> None:
    """Add a child's wrench (or momentum) to what link i carries."""
    if carried[i] is None:
        carried[i] = wrench
    else:
        carried[i] = add(carried[i][0], wrench[0]), add(carried[i][1], wrench[1])


def forward_motion(links, moves, qd, qdd, gravity, at_joints=False):
    """(w, dw, a) of each link, in its frame, a at its origin (``at_joints``: at its joint
    origin o'_i); gravity as a base acceleration. ``moves``: see ``steps``."""
    base = ZERO3, ZERO3, scale(-1.0, gravity)
    parent = parents(links)
    at_origins, motion = [], []
    for i, (link, (rot, p0), qd_i, qdd_i) in enumerate(zip(links, moves, qd, qdd)):
        w, dw, a = base if parent[i] < 0 else at_origins[parent[i]]
        if p0 is not None:  # the joint origin's acceleration, in frame i-1
            a = add(swept(w, dw, p0), a)
        if link.prismatic:  # sliding: qdd e, and Coriolis 2 w x (qd e)
            a = add(a, scale(qdd_i, link.e), cross(scale(2.0 * qd_i, w), link.e))
            w, dw = to_child(link, None, w), to_child(link, None, dw)
        else:
            w_parent = to_child(link, rot, w)
            w = add(w_parent, scale(qd_i, link.b))
            dw = add(to_child(link, rot, dw), scale(qdd_i, link.b), cross(w_parent, scale(qd_i, link.b)))
        a_joint = to_child(link, rot, a)
        a = add(swept(w, dw, link.p), a_joint)
        at_origins.append((w, dw, a))
        motion.append((w, dw, a_joint if at_joints else a))
    return motion


def to_parent_wrench(child: Link, move, f, n):
    """A wrench about o'_child in the child's frame, as one about o_parent in the parent's
    (``move``: the child's (Rot, p0), see ``steps``)."""
    rot, p0 = move
    f, n = to_parent(child, rot, f), to_parent(child, rot, n)
    if p0 is not None:
        n = add(n, cross(p0, f))
    return f, n


def crba(links, cs):
    """Joint-space mass matrix M(q) by the composite rigid body algorithm (armature on the
    diagonal).

    Column j is the torque that a unit qdd_j needs with no velocity and no gravity: the
    composite body of link j and its descendants turns about joint j's axis, the other
    links stand still; only joint j's ancestors feel it (M_ij = 0 off that path).
    """
    moves = steps(links, cs)
    turns = [_one_turn(link, rot) for link, (rot, _) in zip(links, moves)]
    n_links = len(links)
    parent, below = parents(links), children(links)
    composite = [None] * n_links
    for i in reversed(range(n_links)):
        m, h, inertia = links[i].m, links[i].h, links[i].I
        for c in below[i]:
            child, (rot, p0), R = links[c], moves[c], turns[c]
            m_c, h_c, inertia_c = composite[c]
            if R is None:
                r, h_c = to_parent(child, rot, child.p), to_parent(child, rot, h_c)
                inertia_c = _rotate_inertia(child, rot, inertia_c)
            else:
                r, h_c, inertia_c = rotate(R, child.p), rotate(R, h_c), turned(R, inertia_c)
            if p0 is not None:
                r = add(r, p0)  # o_i -> o_c, in frame i
            m_c, h_c, inertia_c = shift_inertia(m_c, h_c, inertia_c, r)
            m, h, inertia = m + m_c, add(h, h_c), tuple(x + y for x, y in zip(inertia, inertia_c))
        composite[i] = (m, h, inertia)

    M = [[0.0] * n_links for _ in range(n_links)]
    for j in range(n_links):
        link, (m, h, inertia) = links[j], composite[j]
        if link.prismatic:  # the composite body slides along b: a = b, no dw
            f = scale(m, link.b)
            n = add(cross(h, link.b), cross(link.p, f))
        else:
            a = cross(link.b, link.p)  # acceleration of o_j
            f = add(scale(m, a), cross(link.b, h))
            n = add(inertia_times(inertia, link.b), cross(h, a), cross(link.p, f))
        M[j][j] = dot(link.b, f if link.prismatic else n) + link.armature
        k = j  # up the ancestors: only they feel joint j's acceleration
        while parent[k] >= 0:
            i = parent[k]
            child, move, R = links[k], moves[k], turns[k]
            if R is None:
                f, n = to_parent_wrench(child, move, f, n)
            else:
                f, n = rotate(R, f), rotate(R, n)
                if move[1] is not None:
                    n = add(n, cross(move[1], f))
            n = add(n, cross(links[i].p, f))
            M[i][j] = M[j][i] = dot(links[i].b, f if links[i].prismatic else n)
            k = i
    return M


def _one_turn(link: Link, rot):
    """R_i = R0 Rot R1 as one matrix when the turn is about an axis other than z and a fixed
    rotation goes with it (then every vector crba moves to the parent's frame turns once,
    not two or three times: fewer operations); None otherwise (a DH row, a turn about z)."""
    if rot is None or link.u == Z_AXIS or (link.R0 is None and link.R1 is None):
        return None
    R = rot if link.R1 is None else _product(rot, link.R1)
    return R if link.R0 is None else _product(link.R0, R)


def _product(A, B) -> Rotation:
    """A B, the constants 0 and +-1 left out."""
    return tuple(tuple(combination((A[j][k], B[k][l]) for k in range(3)) for l in range(3)) for j in range(3))


def _rotate_inertia(link, rot, inertia):
    """R I R^T for the joint rotation R_i = R0 Rot R1, one factor after the other (a turn
    about z in closed form, fewer operations than by columns)."""
    if link.R1 is not None:
        inertia = turned(link.R1, inertia)
    if rot is not None:
        inertia = turned_about(rot, inertia, 2) if link.u == Z_AXIS else turned(rot, inertia)
    return inertia if link.R0 is None else turned(link.R0, inertia)
