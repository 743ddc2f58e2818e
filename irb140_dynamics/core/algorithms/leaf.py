"""A link with no children in its joint frame before its turn (``recursions.rnea``).

There its motion is its parent's (the joint's R0 applied, a permutation) with no turn: the
three vectors of its motion and the two of its wrench are turned once fewer; its inertia
turns instead, which costs a few operations where its products with the turn's axis are
the constant 0 (about its joint origin, in its joint frame): the double-angle form of
``rotations.turned_about``.
"""

from __future__ import annotations

from irb140_dynamics.core.algorithms.rotations import INERTIA_INDEX, rotate, rotate_back, turned, turned_about
from irb140_dynamics.core.algorithms.vectors import add, cross, inertia_times, scale, swept
from irb140_dynamics.core.model.rigid_body import shift_inertia


def cheap_turn_axis(link) -> int | None:
    """k when a revolute link turns about the coordinate axis k (either sign) and its inertia
    about its joint origin, in its joint frame, has the constant 0 as its products with that
    axis (then turning it costs a few operations: ``turned_about``); None otherwise. Read on
    the constants' zeros only, the same for floats and a kernel's inputs."""
    axes = [k for k, x in enumerate(link.u) if x != 0.0]
    if link.prismatic or len(axes) != 1:
        return None
    k = axes[0]
    inertia, h, p = link.I, link.h, link.p
    if link.R1 is not None:  # a permutation (else the turn is fused): exact
        inertia, h, p = turned(link.R1, inertia), rotate(link.R1, h), rotate(link.R1, p)

    def zero(x) -> bool:
        return isinstance(x, float) and x == 0.0

    def product_zero(a) -> bool:  # I_ak - (p_a h_k + h_a p_k) - m p_a p_k, see shift_inertia
        return (
            zero(inertia[INERTIA_INDEX[a, k]])
            and (zero(p[a]) or zero(h[k]))
            and (zero(h[a]) or zero(p[k]))
            and (zero(link.m) or zero(p[a]) or zero(p[k]))
        )

    return k if product_zero((k + 1) % 3) and product_zero((k + 2) % 3) else None


def leaf_wrench(link, move, motion, qd_i, qdd_i, carried, axis: int):
    """(f, n) of a link with no children (and its ``carried`` external wrench), n about its
    joint origin o'_i, both in its joint frame before the turn (R0 applied): there its
    motion is its parent's with no turn (three vectors turned fewer, and the wrench turned
    back fewer), and its inertia turns instead (about the coordinate ``axis``, by the double
    angle)."""
    rot, p0 = move
    w, dw, a = motion
    if p0 is not None:
        a = add(swept(w, dw, p0), a)
    if link.R0 is not None:
        w, dw, a = (rotate_back(link.R0, v) for v in (w, dw, a))
    spin = scale(qd_i, link.u)
    dw = add(dw, scale(qdd_i, link.u), cross(w, spin))
    w = add(w, spin)
    m, h, inertia = shift_inertia(link.m, link.h, link.I, link.p)
    if link.R1 is not None:
        h, inertia = rotate(link.R1, h), turned(link.R1, inertia)
    h, inertia = rotate(rot, h), turned_about(rot, inertia, axis)
    force = add(swept(w, dw, h), scale(m, a))
    # w x (I w) by columns: the turned inertia's entries are computed, not the constants
    # gyroscopic reads (a zero there may be a kernel's input)
    moment = add(inertia_times(inertia, dw), cross(w, inertia_times(inertia, w)), cross(h, a))
    if carried is not None:
        f, n = carried
        n = add(n, cross(link.p, f))
        for R in (link.R1, rot):
            if R is not None:
                f, n = rotate(R, f), rotate(R, n)
        force, moment = add(force, f), add(moment, n)
    return force, moment
