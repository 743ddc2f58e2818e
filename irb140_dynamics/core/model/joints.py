"""Joints: where each joint sits and how it moves, its limits, friction and rotor inertia.

Units: m, rad, rad/s, rad/s^2, N m, N m s/rad, kg m^2 for revolute joints; for prismatic
joints q is in m, qd in m/s, qdd in m/s^2, the effort in N, viscous friction in N s/m,
Coulomb friction in N and armature in kg.

A revolute joint i moves link i relative to link i-1 by

    T_i(q_i) = pre_i * Rot(axis_i, q_i + offset_i) * post_i

where pre and post are fixed placements. Link i's frame is the frame after ``post``; its
inertial parameters are given in it. Two ways of writing a joint fill these in:

- a standard DH row, A_i = Rot_z(q_i + theta_offset) Trans_z(d) Trans_x(a) Rot_x(alpha):
  pre = identity, axis = z, offset = theta_offset, post = Trans(a, 0, d) Rot_x(alpha); link
  i's frame is DH frame i;
- URDF form: pre = the joint's <origin> in the parent link's frame, axis = its <axis>,
  offset = 0, post = identity; link i's frame is the URDF child link's frame.

The *joint frame* is the frame after pre * Rot, before post: its origin is on the joint
axis. For URDF joints it is the link frame; for DH rows it is frame i-1 turned by theta_i.

A prismatic joint (``kind`` "prismatic", URDF form only) slides instead of turning:

    T_i(q_i) = pre_i * Trans(axis_i * q_i) * post_i
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.model.rigid_body import (
    MAX_LENGTH,
    ZERO3,
    ModelError,
    RigidBody,
    Validated,
    Vector3,
    capped,
    finite_number,
    finite_numbers,
)

Z_AXIS: Vector3 = (0.0, 0.0, 1.0)
KINDS = ("revolute", "prismatic")
MAX_FRICTION = 1e6  # sanity cap of viscous [N m s/rad], Coulomb [N m] friction and armature [kg m^2]
# Sanity cap of a torque limit (a prismatic joint's force [N]): wide, to keep 1e300 out (it
# overflows the payload proofs' sums), not to judge the robot. The nodes' torque_limit
# parameters have this range, so a parameter and a URDF's effort are refused alike.
MAX_TORQUE_LIMIT = 1e7  # N m


_validated = Validated()  # the placements and joints validated here


@dataclass(frozen=True)
class DH:
    """One standard DH row: a [m], alpha [rad], d [m], theta_offset [rad]."""

    a: float = 0.0
    alpha: float = 0.0
    d: float = 0.0
    theta_offset: float = 0.0


@dataclass(frozen=True)
class Placement:
    """A fixed rigid transform Trans(xyz) Rot(rpy), as a URDF <origin>: the rotation is
    Rot_z(yaw) Rot_y(pitch) Rot_x(roll) for rpy = (roll, pitch, yaw) [rad]; xyz [m]."""

    xyz: Vector3 = ZERO3
    rpy: Vector3 = ZERO3

    @property
    def is_identity(self) -> bool:
        return self.xyz == ZERO3 and self.rpy == ZERO3

    def rotation(self) -> np.ndarray:
        """The 3x3 rotation, entries within 1e-15 of 0 or +-1 made exact (cos(pi/2) is 6e-17)."""
        return snap(rpy_matrix(self.rpy))

    def matrix(self) -> np.ndarray:
        """The 4x4 homogeneous transform."""
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = self.rotation(), self.xyz
        return T

    def flat(self) -> list[float]:
        """[x, y, z, roll, pitch, yaw], the parameter form."""
        return [*self.xyz, *self.rpy]

    @classmethod
    def validated(cls, field: str, value) -> Placement:
        """From [x, y, z, roll, pitch, yaw] (or a Placement), or ModelError naming ``field``."""
        if value in _validated:
            return value
        if isinstance(value, Placement):
            value = value.flat()
        numbers = finite_numbers(field, value, 6)
        capped(field, "|xyz|", math.hypot(*numbers[:3]), MAX_LENGTH, "m")
        return _validated.add(cls(numbers[:3], numbers[3:]))


def rpy_matrix(rpy) -> np.ndarray:
    roll, pitch, yaw = rpy
    cr, sr, cp, sp, cy, sy = (f(x) for x in (roll, pitch, yaw) for f in (math.cos, math.sin))
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def matrix_rpy(R) -> Vector3:
    """(roll, pitch, yaw) of a rotation matrix, the inverse of rpy_matrix."""
    R = np.asarray(R, dtype=float)
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if math.hypot(R[0, 0], R[1, 0]) < 1e-12:  # gimbal lock: yaw taken as 0
        return (math.atan2(-R[1, 2], R[1, 1]), pitch, 0.0)
    return (math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0]))


def snap(R: np.ndarray) -> np.ndarray:
    """Entries within 1e-15 of 0 or +-1 made exact, so that generated code folds them."""
    R = np.array(R, dtype=float)
    for target in (0.0, 1.0, -1.0):
        R[np.abs(R - target) < 1e-15] = target
    return R


@dataclass(frozen=True)
class Friction:
    """Joint friction: tau_f = viscous qd + coulomb tanh(qd / smoothing velocity)."""

    viscous: float = 0.0  # N m s/rad
    coulomb: float = 0.0  # N m


@dataclass(frozen=True)
class Joint:
    """A revolute or prismatic joint, the link it moves, its limits, friction and rotor inertia.

    The kinematics are a DH row (``dh``), or, with ``dh`` None, URDF form: ``origin`` (the
    joint frame in the parent link's frame) and ``axis`` (a unit vector in the joint frame).
    Limits of 0 mean none given. ``kind`` "prismatic" (URDF form only): the joint slides
    along ``axis``, its limits, effort and friction in m, N (see the module). ``physical``
    False: the link's inertia is checked finite only, not physically consistent (a vendor
    URDF's numbers, taken as given with a warning by the URDF loader).
    """

    name: str
    dh: DH | None = None
    link: RigidBody = RigidBody()
    position_limits: tuple[float, float] = (-math.pi, math.pi)
    torque_limit: float = 0.0  # N m
    origin: Placement = Placement()
    axis: Vector3 = Z_AXIS
    velocity_limit: float = 0.0  # rad/s
    acceleration_limit: float = 0.0  # rad/s^2
    friction: Friction = Friction()
    armature: float = 0.0  # kg m^2: rotor inertia reflected through the gear, on M's diagonal
    kind: str = "revolute"
    physical: bool = True

    @property
    def prismatic(self) -> bool:
        return self.kind == "prismatic"

    @property
    def pre(self) -> Placement:
        return Placement() if self.dh is not None else self.origin

    @property
    def turning_axis(self) -> Vector3:
        return Z_AXIS if self.dh is not None else self.axis

    @property
    def offset(self) -> float:
        return self.dh.theta_offset if self.dh is not None else 0.0

    @property
    def post(self) -> Placement:
        if self.dh is None:
            return Placement()
        return Placement((self.dh.a, 0.0, self.dh.d), (self.dh.alpha, 0.0, 0.0))

    def transform(self, q: float) -> np.ndarray:
        """T_i(q) = pre Rot(axis, q + offset) post (prismatic: pre Trans(axis q) post), 4x4."""
        move = np.eye(4)
        if self.prismatic:
            move[:3, 3] = np.asarray(self.axis, dtype=float) * q
        else:
            move[:3, :3] = axis_rotation(self.turning_axis, q + self.offset)
        return self.pre.matrix() @ move @ self.post.matrix()


def axis_rotation(axis, angle: float) -> np.ndarray:
    """Rot(axis, angle) for a unit axis (Rodrigues)."""
    u = np.asarray(axis, dtype=float)
    c, s = math.cos(angle), math.sin(angle)
    cross = np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])
    return c * np.eye(3) + s * cross + (1.0 - c) * np.outer(u, u)


def validated_joint(j: Joint) -> Joint:
    """The joint with every value checked (ModelError naming ``<joint>.<field>``); one this
    function returned comes back at once."""
    if j in _validated:
        return j
    return _validated.add(_validate_joint(j))


def _validate_joint(j: Joint) -> Joint:
    name = param_prefix(j.name)
    if j.kind not in KINDS:
        raise ModelError(f"{name}.type", f"must be one of {', '.join(KINDS)}, got {j.kind!r}")
    if j.kind == "prismatic" and j.dh is not None:
        raise ModelError(f"{name}.type", "a prismatic joint is given in URDF form (origin, axis), not as a DH row")
    dh = None
    if j.dh is not None:
        dh = DH(*finite_numbers(f"{name}.dh", (j.dh.a, j.dh.alpha, j.dh.d, j.dh.theta_offset), 4))
        capped(f"{name}.dh", "|a| and |d|", max(abs(dh.a), abs(dh.d)), MAX_LENGTH, "m")
    origin = Placement.validated(f"{name}.origin", j.origin)
    axis = finite_numbers(f"{name}.axis", j.axis, 3)
    norm = math.hypot(*axis)
    if not 0.5 < norm < 2.0:
        raise ModelError(f"{name}.axis", f"must be a unit vector, got {list(axis)}")
    axis = Z_AXIS if axis == Z_AXIS else tuple(x / norm for x in axis)
    lower, upper = finite_numbers(f"{name}.position_limits", j.position_limits, 2)
    if lower > upper:
        raise ModelError(f"{name}.position_limits", f"lower {lower} > upper {upper}")
    nonnegative = {
        "torque_limit": (j.torque_limit, "(0 = none)"),
        "velocity_limit": (j.velocity_limit, "(0 = none)"),
        "acceleration_limit": (j.acceleration_limit, "(0 = none)"),
        "friction.viscous": (j.friction.viscous, ""),
        "friction.coulomb": (j.friction.coulomb, ""),
        "armature": (j.armature, ""),
    }
    values = {}
    for field, (value, note) in nonnegative.items():
        x = finite_number(f"{name}.{field}", value)
        if x < 0.0:
            raise ModelError(f"{name}.{field}", f"must be >= 0 {note}, got {x}".replace("  ", " "))
        values[field] = x
    for field, cap, unit in (
        ("torque_limit", MAX_TORQUE_LIMIT, "N m"),
        ("friction.viscous", MAX_FRICTION, "N m s/rad"),
        ("friction.coulomb", MAX_FRICTION, "N m"),
        ("armature", MAX_FRICTION, "kg m^2"),
    ):
        capped(f"{name}.{field}", "", values[field], cap, unit)
    link = RigidBody.validated(f"{name}.link", j.link.mass, j.link.com, j.link.inertia, physical=bool(j.physical))
    return Joint(
        j.name,
        dh,
        link,
        (lower, upper),
        values["torque_limit"],
        origin,
        axis,
        values["velocity_limit"],
        values["acceleration_limit"],
        Friction(values["friction.viscous"], values["friction.coulomb"]),
        values["armature"],
        j.kind,
        bool(j.physical),
    )


_PARAMETER_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")


def param_prefix(name: str) -> str:
    """The parameter prefix of a joint name: the name itself when it is one ([A-Za-z][A-Za-z0-9_]*),
    else the name with each other character made '_' (and 'j_' before a leading non-letter):
    "arm-left.1" -> "arm_left_1". The joint keeps its name; only parameters use this."""
    if _PARAMETER_NAME.match(name):
        return name
    prefix = re.sub(r"[^A-Za-z0-9_]", "_", name)
    return prefix if prefix[:1].isalpha() and prefix.isascii() else f"j_{prefix}"
