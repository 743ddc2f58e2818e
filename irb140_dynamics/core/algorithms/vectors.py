"""3-vectors as tuples of scalars (any type with + - *, see ``recursions``), and an inertia
(xx, yy, zz, xy, xz, yz) times a vector."""

from __future__ import annotations


def add(*vectors):
    return tuple(sum(components[1:], components[0]) for components in zip(*vectors))


def scale(k, v):
    return (k * v[0], k * v[1], k * v[2])


def dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def cross(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def inertia_times(inertia, v):
    xx, yy, zz, xy, xz, yz = inertia
    return (
        xx * v[0] + xy * v[1] + xz * v[2],
        xy * v[0] + yy * v[1] + yz * v[2],
        xz * v[0] + yz * v[1] + zz * v[2],
    )


def swept(w, dw, v):
    """dw x v + w x (w x v), the acceleration of a point v fixed on a body turning at w, dw
    (less its origin's), by the 3 x 3 (dw~ + w~ w~) whose w~ w~ = w w^T - |w|^2 1 takes six
    products of w's components: one body's sweeps of several points share them (in a traced
    kernel, where the tracer merges the repeated products)."""
    xx, yy, zz = w[0] * w[0], w[1] * w[1], w[2] * w[2]
    xy, xz, yz = w[0] * w[1], w[0] * w[2], w[1] * w[2]
    return (
        (xy - dw[2]) * v[1] + (xz + dw[1]) * v[2] - (yy + zz) * v[0],
        (xy + dw[2]) * v[0] + (yz - dw[0]) * v[2] - (xx + zz) * v[1],
        (xz - dw[1]) * v[0] + (yz + dw[0]) * v[1] - (xx + yy) * v[2],
    )


def gyroscopic(inertia, w):
    """w x (I w), as ((Izz - Iyy) w_y w_z, ...) where the products of inertia are the constant 0
    (the payload's link's moments of inertia may be a kernel's inputs: their differences are
    then computed, once)."""
    xx, yy, zz, xy, xz, yz = inertia
    if all(type(x) is float and x == 0.0 for x in (xy, xz, yz)):
        return ((zz - yy) * (w[1] * w[2]), (xx - zz) * (w[2] * w[0]), (yy - xx) * (w[0] * w[1]))
    return cross(w, inertia_times(inertia, w))
