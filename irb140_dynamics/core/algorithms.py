"""The dynamics algorithms, written once on scalar components.

Notation follows the report (Luh-Walker-Paul recursive Newton-Euler), everything of link i
expressed in its own frame i:

    q, qd, qdd   joint positions, velocities, accelerations
    w, dw, a     angular velocity, angular acceleration, linear acceleration of origin o_i
    b            joint i's axis z_{i-1}, in frame i
    p            o_{i-1} -> o_i, in frame i
    m, h, I      link mass, first moment m*c, inertia about o_i
    f, n         force and moment (about o_{i-1}) that link i-1 exerts on link i
    tau          joint torques, tau_i = b . n_i

Vectors are 3-tuples. A scalar may be a float, a NumPy array (many states at once) or a
symbol of ``codegen`` (which turns these functions into straight-line code). So only
``+ - *`` are used, and the joint angles enter as (cos, sin) pairs computed by the caller.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .rigid_body import ZERO3, Vector3, Inertia6, shift_inertia


@dataclass(frozen=True)
class Link:
    """Constants of link i for the recursions, in frame i."""

    theta_offset: float
    ca: float  # cos(alpha)
    sa: float  # sin(alpha)
    p: Vector3
    m: float
    h: Vector3
    I: Inertia6

    @property
    def b(self) -> Vector3:
        return (0.0, self.sa, self.ca)


def chain(model) -> tuple[Link, ...]:
    """The per-link constants of a RobotModel (payload merged into the last link)."""
    links = []
    for joint, body in zip(model.joints, model.bodies):
        ca, sa = _exact(math.cos(joint.dh.alpha)), _exact(math.sin(joint.dh.alpha))
        m, h, inertia = body.about_origin()
        p = (joint.dh.a, joint.dh.d * sa, joint.dh.d * ca)
        links.append(Link(joint.dh.theta_offset, ca, sa, p, m, h, inertia))
    return tuple(links)


def _exact(x: float) -> float:
    """Snap cos/sin of a right-angle multiple to exactly 0 or +-1 (cos(pi/2) is 6e-17)."""
    for target in (0.0, 1.0, -1.0):
        if abs(x - target) < 1e-15:
            return target
    return x


# -- 3-vector algebra ---------------------------------------------------------------


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


def to_child(link: Link, c, s, v):
    """R_i^T v: a vector of frame i-1 expressed in frame i (R_i = Rot_z(theta) Rot_x(alpha))."""
    u = c * v[0] + s * v[1]
    w = c * v[1] - s * v[0]
    return (u, link.ca * w + link.sa * v[2], link.ca * v[2] - link.sa * w)


def to_parent(link: Link, c, s, v):
    """R_i v: a vector of frame i expressed in frame i-1."""
    u = link.ca * v[1] - link.sa * v[2]
    return (c * v[0] - s * u, s * v[0] + c * u, link.sa * v[1] + link.ca * v[2])


# -- algorithms ---------------------------------------------------------------------


def rnea(links, cs, qd, qdd, gravity, f_ext=ZERO3, n_ext=ZERO3):
    """Joint torques tau(q, qd, qdd) by the recursive Newton-Euler algorithm.

    ``cs`` holds (cos, sin) of each joint angle theta_i = q_i + theta_offset_i.
    (f_ext, n_ext) is the wrench the environment exerts on the flange, in the flange
    frame, the moment taken about the flange origin; tau balances it (a load pressing on
    the flange raises tau like a weight would).
    """
    w, dw, a = ZERO3, ZERO3, scale(-1.0, gravity)  # gravity as a base acceleration
    motion = []
    for link, (c, s), qd_i, qdd_i in zip(links, cs, qd, qdd):
        w_parent = to_child(link, c, s, w)
        w = add(w_parent, scale(qd_i, link.b))
        dw = add(to_child(link, c, s, dw), scale(qdd_i, link.b), cross(w_parent, scale(qd_i, link.b)))
        a = add(to_child(link, c, s, a), cross(dw, link.p), cross(w, cross(w, link.p)))
        motion.append((w, dw, a))

    tau = [0.0] * len(links)
    f, n = scale(-1.0, f_ext), scale(-1.0, n_ext)
    for i in reversed(range(len(links))):
        link, (w, dw, a) = links[i], motion[i]
        if i + 1 < len(links):
            child, (c, s) = links[i + 1], cs[i + 1]
            f, n = to_parent(child, c, s, f), to_parent(child, c, s, n)
        force = add(scale(link.m, a), cross(dw, link.h), cross(w, cross(w, link.h)))
        moment = add(inertia_times(link.I, dw), cross(w, inertia_times(link.I, w)), cross(link.h, a))
        f = add(force, f)
        n = add(moment, n, cross(link.p, f))
        tau[i] = dot(link.b, n)
    return tau


def crba(links, cs):
    """Joint-space mass matrix M(q) by the composite rigid body algorithm.

    Column j is the torque that a unit qdd_j needs with no velocity and no gravity: the
    composite body j..n turns about joint j's axis, links before j stand still.
    """
    n_links = len(links)
    composite = [None] * n_links
    for i in reversed(range(n_links)):
        m, h, inertia = links[i].m, links[i].h, links[i].I
        if i + 1 < n_links:
            child, (c, s) = links[i + 1], cs[i + 1]
            m_c, h_c, inertia_c = composite[i + 1]
            m_c, h_c, inertia_c = shift_inertia(
                m_c,
                to_parent(child, c, s, h_c),
                _rotate_inertia(child, c, s, inertia_c),
                to_parent(child, c, s, child.p),
            )
            m, h, inertia = m + m_c, add(h, h_c), tuple(x + y for x, y in zip(inertia, inertia_c))
        composite[i] = (m, h, inertia)

    M = [[0.0] * n_links for _ in range(n_links)]
    for j in range(n_links):
        link, (m, h, inertia) = links[j], composite[j]
        a = cross(link.b, link.p)  # acceleration of o_j
        f = add(scale(m, a), cross(link.b, h))
        n = add(inertia_times(inertia, link.b), cross(h, a), cross(link.p, f))
        M[j][j] = dot(link.b, n)
        for i in reversed(range(j)):
            child, (c, s) = links[i + 1], cs[i + 1]
            f, n = to_parent(child, c, s, f), to_parent(child, c, s, n)
            n = add(n, cross(links[i].p, f))
            M[i][j] = M[j][i] = dot(links[i].b, n)
    return M


def _rotate_inertia(link, c, s, inertia):
    """R I R^T for the joint rotation R_i: columns of R I, then R (R I)^T."""
    xx, yy, zz, xy, xz, yz = inertia
    columns = [to_parent(link, c, s, col) for col in ((xx, xy, xz), (xy, yy, yz), (xz, yz, zz))]
    rows_of_ri = list(zip(*columns))
    col0 = to_parent(link, c, s, rows_of_ri[0])
    col1 = to_parent(link, c, s, rows_of_ri[1])
    col2 = to_parent(link, c, s, rows_of_ri[2])
    return (col0[0], col1[1], col2[2], col1[0], col2[0], col2[1])


def christoffel_coriolis(links, cs, qd):
    """The Coriolis matrix C(q, qd) from the Christoffel symbols of M(q).

    C_ij = sum_k 1/2 (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) qd_k, so that C qd is the
    Coriolis/centrifugal torque and Mdot - 2C is skew-symmetric. The partial derivatives
    of M are exact: crba runs on dual numbers carrying d/dq of each scalar.
    """
    n = len(links)
    dual_cs = [
        (Dual(c, _unit(n, k, -s)), Dual(s, _unit(n, k, c))) for k, (c, s) in enumerate(cs)
    ]
    M = crba(links, dual_cs)
    dM = [[[_partial(M[i][j], k) for k in range(n)] for j in range(n)] for i in range(n)]
    return [
        [
            sum(0.5 * (dM[i][j][k] + dM[i][k][j] - dM[j][k][i]) * qd[k] for k in range(n))
            for j in range(n)
        ]
        for i in range(n)
    ]


class Dual:
    """A scalar with its partial derivatives d/dq_k (forward-mode differentiation)."""

    __slots__ = ("value", "d")

    def __init__(self, value, d):
        self.value, self.d = value, d

    def __add__(self, other):
        if isinstance(other, Dual):
            return Dual(self.value + other.value, tuple(x + y for x, y in zip(self.d, other.d)))
        return Dual(self.value + other, self.d)

    __radd__ = __add__

    def __neg__(self):
        return Dual(-self.value, tuple(-x for x in self.d))

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if isinstance(other, Dual):
            return Dual(
                self.value * other.value,
                tuple(x * other.value + self.value * y for x, y in zip(self.d, other.d)),
            )
        return Dual(self.value * other, tuple(x * other for x in self.d))

    __rmul__ = __mul__


def _unit(n, k, value):
    return tuple(value if i == k else 0.0 for i in range(n))


def _partial(x, k):
    return x.d[k] if isinstance(x, Dual) else 0.0
