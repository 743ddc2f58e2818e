"""Rigid-body inertial parameters and their validation.

Units: kg, m, kg m^2. An inertia is six numbers (Ixx, Iyy, Izz, Ixy, Ixz, Iyz), the
tensor's entries (Ixy is the tensor entry, i.e. minus the product of inertia integral).

Sanity caps: a mass is at most MAX_MASS, a centre of mass at most MAX_LENGTH from its
frame's origin, an inertia entry at most MAX_INERTIA in size (and the model caps DH lengths
and gravity, see ``model``). They are far beyond any arm, and they keep every quantity the
algorithms derive finite: m c <= 1e9 kg m, the inertia about a joint origin <= 2.1e12 kg m^2
(payload merged into the last link included), and so the torques at any state of sane
speeds. Without them 1e200 kg, or a CoM 1e200 m out, would overflow to inf or nan.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

Vector3 = tuple[float, float, float]
Inertia6 = tuple[float, float, float, float, float, float]

ZERO3: Vector3 = (0.0, 0.0, 0.0)
ZERO6: Inertia6 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

MAX_MASS = 1e6  # kg
MAX_LENGTH = 1e3  # m: |CoM|, and the DH lengths |a|, |d|
MAX_INERTIA = 1e6  # kg m^2: each entry of an inertia about the CoM
MAX_GRAVITY = 1e3  # m/s^2: |g|


class ModelError(ValueError):
    """An invalid model value; ``field`` is the parameter name that holds it."""

    def __init__(self, field: str, reason: str):
        super().__init__(f"{field}: {reason}")
        self.field = field
        self.reason = reason


class Validated:
    """The objects a validating function returned, while they live, by identity: validating
    one of them again is free (a model rebuilt for a new payload re-validates only that)."""

    def __init__(self):
        self._by_id: weakref.WeakValueDictionary[int, object] = weakref.WeakValueDictionary()

    def __contains__(self, obj) -> bool:
        return self._by_id.get(id(obj)) is obj

    def add(self, obj):
        self._by_id[id(obj)] = obj
        return obj


def finite_numbers(field: str, value, length: int | None = None) -> tuple[float, ...]:
    """``value`` as a tuple of finite floats (of ``length`` when given), or ModelError."""
    try:
        array = np.atleast_1d(np.asarray(value))
        if array.dtype.kind not in "iuf":  # no strings, booleans or other objects
            raise TypeError
        numbers = tuple(float(x) for x in array.astype(float))
    except (TypeError, ValueError):
        raise ModelError(field, f"expected numbers, got {value!r}") from None
    if length is not None and len(numbers) != length:
        raise ModelError(field, f"expected {length} numbers, got {len(numbers)}")
    if not all(math.isfinite(x) for x in numbers):
        raise ModelError(field, f"must be finite, got {list(numbers)}")
    return numbers


def finite_number(field: str, value) -> float:
    if isinstance(value, (list, tuple, np.ndarray)) and np.ndim(value) != 0:
        raise ModelError(field, f"expected one number, got {value!r}")
    return finite_numbers(field, value, 1)[0]


def capped(field: str, what: str, size: float, cap: float, unit: str) -> None:
    """ModelError unless size <= cap (one of the sanity caps above)."""
    if size > cap:
        raise ModelError(field, f"{what} must be <= {cap:g} {unit} (sanity cap), got {size:g}".lstrip())


def checked_mass(field: str, mass) -> float:
    """A mass as a float: finite, >= 0, at most MAX_MASS; else ModelError naming ``field``."""
    m = finite_number(field, mass)
    if m < 0.0:
        raise ModelError(field, f"must be >= 0, got {m}")
    capped(field, "", m, MAX_MASS, "kg")
    return m


def inertia_matrix(inertia: Sequence[float]) -> np.ndarray:
    xx, yy, zz, xy, xz, yz = inertia
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def inertia_entries(matrix) -> Inertia6:
    """The six entries (xx, yy, zz, xy, xz, yz) of a symmetric 3 x 3 inertia, as floats:
    ``inertia_matrix`` undone."""
    return tuple(float(matrix[j][k]) for j, k in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)))


def validate_inertia(field: str, inertia: Sequence[float], physical: bool = True) -> Inertia6:
    """Six finite numbers forming a physically possible inertia tensor (``physical`` False:
    six finite numbers within the cap), or ModelError."""
    inertia = finite_numbers(field, inertia, 6)
    capped(field, "each |entry|", max(map(abs, inertia)), MAX_INERTIA, "kg m^2")
    if physical:
        physical_inertia(field, inertia)
    return inertia


def physical_inertia(field: str, inertia: Sequence[float]) -> None:
    """ModelError unless the inertia is positive semi-definite and obeys the triangle inequality."""
    moments = np.linalg.eigvalsh(inertia_matrix(inertia))
    tol = 1e-12 * max(1.0, float(np.max(np.abs(moments))))
    if moments[0] < -tol:
        raise ModelError(field, f"not positive semi-definite (principal moments {moments.tolist()})")
    if moments[0] + moments[1] < moments[2] - tol:
        raise ModelError(field, f"principal moments {moments.tolist()} break the triangle inequality")


@dataclass(frozen=True)
class RigidBody:
    """A rigid body in its own frame: mass, centre of mass, inertia about the centre of mass."""

    mass: float = 0.0
    com: Vector3 = ZERO3
    inertia: Inertia6 = ZERO6

    @classmethod
    def validated(cls, field: str, mass, com=ZERO3, inertia=ZERO6, physical: bool = True) -> RigidBody:
        """Build from raw values; errors name ``field.mass``, ``field.com``, ``field.inertia``.
        ``physical`` False: the inertia need not be physically consistent (finite, capped)."""
        m = checked_mass(f"{field}.mass", mass)
        c = finite_numbers(f"{field}.com", com, 3)
        capped(f"{field}.com", "|com|", math.hypot(*c), MAX_LENGTH, "m")
        body = cls(m, c, validate_inertia(f"{field}.inertia", inertia, physical))
        return VALIDATED_BODIES.add(body) if physical else body

    @classmethod
    def checked(cls, field: str, body: RigidBody) -> RigidBody:
        """``body`` validated (see ``validated``); at once if it came from there."""
        if body in VALIDATED_BODIES:
            return body
        return cls.validated(field, body.mass, body.com, body.inertia)

    def about_origin(self) -> tuple[float, Vector3, Inertia6]:
        """(m, h, I_o): mass, first moment m*com, and inertia about the frame origin."""
        return shift_inertia(self.mass, ZERO3, self.inertia, self.com)


VALIDATED_BODIES = Validated()


def shift_inertia(m, h, inertia, r):
    """Move the reference point of an inertia from O to O' = O - r (r points from O' to O).

    (m, h, I) are mass, first moment and inertia about O; returns (m, h', I') about O'.
    Works on any scalar type (float, NumPy array, traced symbol).
    """
    xx, yy, zz, xy, xz, yz = inertia
    rx, ry, rz = r
    hx, hy, hz = h
    hr2 = 2 * (hx * rx + hy * ry + hz * rz)
    r2 = rx * rx + ry * ry + rz * rz
    new_h = (hx + m * rx, hy + m * ry, hz + m * rz)
    new_inertia = (
        xx + hr2 - 2 * rx * hx + m * (r2 - rx * rx),
        yy + hr2 - 2 * ry * hy + m * (r2 - ry * ry),
        zz + hr2 - 2 * rz * hz + m * (r2 - rz * rz),
        xy - (rx * hy + hx * ry) - m * rx * ry,
        xz - (rx * hz + hx * rz) - m * rx * rz,
        yz - (ry * hz + hy * rz) - m * ry * rz,
    )
    return m, new_h, new_inertia


def combine(a: RigidBody, b: RigidBody) -> RigidBody:
    """The rigid union of two bodies given in the same frame."""
    m = a.mass + b.mass
    if m == 0.0:
        return RigidBody(0.0, ZERO3, tuple(x + y for x, y in zip(a.inertia, b.inertia)))
    _, ha, ia = a.about_origin()
    _, hb, ib = b.about_origin()
    com = tuple((x + y) / m for x, y in zip(ha, hb))
    about_origin = tuple(x + y for x, y in zip(ia, ib))
    # back from the origin to the combined centre of mass: I_c = I_o - m (|c|^2 1 - c c^T)
    _, _, shift = shift_inertia(m, ZERO3, ZERO6, com)
    return RigidBody(m, com, tuple(x - y for x, y in zip(about_origin, shift)))


def checked_body(field: str, body) -> RigidBody:
    """A RigidBody argument checked as ``RigidBody.validated`` checks raw values (ModelError
    naming field.mass, field.com, field.inertia). The mass is checked on every call, the
    shape (CoM and inertia) once: it is remembered."""
    if not isinstance(body, RigidBody):
        raise ModelError(field, f"expected a RigidBody, got {body!r}")
    mass = checked_mass(f"{field}.mass", body.mass)
    try:
        shape = _checked_shape(field, tuple(body.com), tuple(body.inertia))
    except TypeError:  # not sequences, or of unhashable things: no memory, the same errors
        shape = RigidBody.validated(field, mass, body.com, body.inertia)
    return RigidBody(mass, shape.com, shape.inertia)


@lru_cache(maxsize=64)
def _checked_shape(field: str, com, inertia) -> RigidBody:
    return RigidBody.validated(field, 0.0, com, inertia)


def placed(body: RigidBody, rotation, translation) -> RigidBody:
    """``body`` given in a frame F, expressed in the frame where F sits at (rotation, translation)."""
    R = np.asarray(rotation, dtype=float)
    com = R @ np.asarray(body.com) + np.asarray(translation, dtype=float)
    return RigidBody(body.mass, tuple(com.tolist()), inertia_entries(R @ inertia_matrix(body.inertia) @ R.T))
