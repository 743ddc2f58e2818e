"""The robot model: a serial chain of revolute joints (see ``joints``: DH rows or URDF form).

Units (SI throughout): m, rad, kg, kg m^2, m/s^2, N m.

Link i is the body moved by joint i. The flange, where the payload sits, is the last link's
frame placed by ``flange`` (identity for DH models: frame n). Gravity is given in the base
frame 0.

A model is immutable. Its flat parameter form (``to_params`` / ``from_params``) uses the
same names as the ROS parameters of the nodes, so that a validation error names the
parameter to fix:

    joint_names                 [name, ...]
    gravity                     [gx, gy, gz]
    payload.mass / .com / .inertia
    friction.smoothing_velocity rad/s, of the Coulomb friction's tanh
    flange                      [x, y, z, roll, pitch, yaw] in the last link (identity if absent)
    flange_joint                the joint whose link carries the flange instead (a tree's)
    <joint>.type                "revolute" (default) or "prismatic" (URDF form only)
    <joint>.dh                  [a, alpha, d, theta_offset], or in URDF form:
    <joint>.origin, .axis       [x, y, z, roll, pitch, yaw] in the parent link; [x, y, z]
    <joint>.link.mass / .com / .inertia
    <joint>.link.physical       true (default); false: the inertia is checked finite only
    <joint>.position_limits     [lower, upper]
    <joint>.torque_limit        N m, 0 = none given
    <joint>.velocity_limit      rad/s, 0 = none given
    <joint>.acceleration_limit  rad/s^2, 0 = none given
    <joint>.friction.viscous    N m s/rad
    <joint>.friction.coulomb    N m
    <joint>.armature            kg m^2

and for a tree or a model with mimic joints (absent for a chain):

    tree.joints                 [name, ...] every moving joint, parents first
    tree.parents                [parent joint's name or "" (the base), ...] per tree.joints
    <joint>.mimic.joint         the joint it follows (a mimic joint only)
    <joint>.mimic.multiplier, <joint>.mimic.offset

(prismatic joints: m, N, N s/m, N, kg). ``<joint>`` is the joint's name when it is a
parameter name ([A-Za-z][A-Za-z0-9_]*), else its ``param_prefix`` ("arm-left.1" ->
"arm_left_1"); ``joint_names`` holds the names themselves.

Besides being finite, masses, lengths, inertias and gravity are within sanity caps (see
``rigid_body``) that keep every number the algorithms derive from them finite.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

from irb140_dynamics.core.model.friction import JointFriction
from irb140_dynamics.core.model.joints import DH, KINDS, Friction, Joint, Placement, param_prefix, validated_joint
from irb140_dynamics.core.model.rigid_body import (
    MAX_GRAVITY,
    ZERO3,
    ModelError,
    RigidBody,
    capped,
    combine,
    finite_number,
    finite_numbers,
    placed,
)
from irb140_dynamics.core.model.tree import Mimic, checked_mimics, checked_parents, tree_from_params, tree_params

MAX_NAME = 200  # characters of a joint name
DEFAULT_SMOOTHING_VELOCITY = 0.01  # rad/s: Coulomb friction reaches 76 % of its level at 0.01 rad/s
__all__ = ["DH", "Friction", "Joint", "Mimic", "ModelError", "Placement", "RobotModel"]


@dataclass(frozen=True)
class RobotModel:
    """A validated model of a serial chain or a kinematic tree; raises ModelError naming
    the bad field.

    ``joints`` are every moving joint, parents before children; ``parent[i]`` is the index
    in ``joints`` of joint i's parent joint (the joint moving the link joint i hangs from),
    -1 for the base (spatial_v2's ``model.parent``); None: a chain, parent[i] = i - 1.
    ``mimics``: per joint, None or the ``Mimic`` it follows (None: no mimic joint). The
    model's coordinates are its independent joints (``joint_names``, ``n``, the states
    q, qd, qdd, tau); the mimic joints follow them (``mimic_matrix``). The payload and the
    flange are on the last joint's link.
    """

    joints: tuple[Joint, ...]
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    payload: RigidBody = field(default_factory=RigidBody)
    flange: Placement = Placement()  # the payload's frame in the last link's frame
    smoothing_velocity: float = DEFAULT_SMOOTHING_VELOCITY  # rad/s, Coulomb friction's tanh
    parent: tuple[int, ...] | None = None  # per joint: its parent joint's index, -1 the base
    mimics: tuple[Mimic | None, ...] | None = None  # per joint: the joint it follows, or None
    flange_joint: str | None = None  # the joint whose link carries the flange; None: the last one

    def __post_init__(self):
        object.__setattr__(self, "joints", tuple(validated_joint(j) for j in self.joints))
        object.__setattr__(self, "gravity", finite_numbers("gravity", self.gravity, 3))
        capped("gravity", "|g|", math.hypot(*self.gravity), MAX_GRAVITY, "m/s^2")
        object.__setattr__(self, "payload", RigidBody.checked("payload", self.payload))
        object.__setattr__(self, "flange", Placement.validated("flange", self.flange))
        smoothing = finite_number("friction.smoothing_velocity", self.smoothing_velocity)
        if not smoothing > 0.0:
            raise ModelError("friction.smoothing_velocity", f"must be > 0, got {smoothing}")
        object.__setattr__(self, "smoothing_velocity", smoothing)
        check_joint_names([j.name for j in self.joints])
        object.__setattr__(self, "parent", checked_parents(self.parent, len(self.joints)))
        object.__setattr__(self, "mimics", checked_mimics(self.mimics, self.joints))
        if self.flange_joint is not None:
            if self.flange_joint not in [j.name for j in self.joints]:
                raise ModelError("flange_joint", f"{str(self.flange_joint)[:80]!r} is not a joint of the model")
            if self.flange_joint == self.joints[-1].name:
                object.__setattr__(self, "flange_joint", None)  # the default, said once

    @property
    def n(self) -> int:
        """The number of independent joints: the length of a state."""
        return len(self.independent)

    @cached_property
    def independent(self) -> tuple[int, ...]:
        """The indices in ``joints`` of the independent joints (all but the mimic joints)."""
        if self.mimics is None:
            return tuple(range(len(self.joints)))
        return tuple(i for i, mimic in enumerate(self.mimics) if mimic is None)

    @property
    def independent_joints(self) -> tuple[Joint, ...]:
        """The independent joints (``joints`` but the mimic joints): one per coordinate, their
        limits the state's (a mimic joint's friction is its joint's: ``friction``)."""
        if self.mimics is None:
            return self.joints
        return tuple(self.joints[i] for i in self.independent)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The independent joints' names, the order of every state."""
        return tuple(self.joints[i].name for i in self.independent)

    @property
    def is_chain(self) -> bool:
        """A serial chain (each joint's parent the joint before), no mimic joint, the flange
        on the last link."""
        return self.mimics is None and self.flange_joint is None and all(p == i - 1 for i, p in enumerate(self.parent))

    @cached_property
    def carrier(self) -> int:
        """The index in ``joints`` of the joint whose link carries the flange and payload."""
        if self.flange_joint is None:
            return len(self.joints) - 1
        return [j.name for j in self.joints].index(self.flange_joint)

    @cached_property
    def coordinates(self) -> tuple[tuple[int, float, float], ...]:
        """Per joint of ``joints``: (k, multiplier, offset), its position being
        multiplier * q_k + offset of the state q; (k, 1.0, 0.0) for an independent joint."""
        index = {self.joints[i].name: k for k, i in enumerate(self.independent)}
        if self.mimics is None:
            return tuple((k, 1.0, 0.0) for k in range(len(self.joints)))
        return tuple(
            (index[j.name], 1.0, 0.0) if m is None else (index[m.joint], m.multiplier, m.offset)
            for j, m in zip(self.joints, self.mimics)
        )

    def mimic_matrix(self):
        """G, (len(joints), n): every joint's velocity is G qd; its torque is carried by the
        independent joints as G^T tau_all (virtual work), M = G^T M_all G."""
        import numpy as np

        G = np.zeros((len(self.joints), self.n))
        for i, (k, multiplier, _) in enumerate(self.coordinates):
            G[i, k] = multiplier
        return G

    def all_positions(self, q):
        """Every joint's position, mimic joints included, from the state q (n numbers)."""
        import numpy as np

        q = np.asarray(q, dtype=float)
        return np.array([multiplier * q[k] + offset for k, multiplier, offset in self.coordinates])

    @property
    def torque_limits(self) -> tuple[float, ...]:
        return tuple(self.joints[i].torque_limit for i in self.independent)

    @property
    def bodies(self) -> tuple[RigidBody, ...]:
        """The moving bodies, the payload merged into the flange's link (the last one's)."""
        bodies = [j.link for j in self.joints]
        payload = self.payload
        if not self.flange.is_identity:
            payload = placed(payload, self.flange.rotation(), self.flange.xyz)
        bodies[self.carrier] = combine(bodies[self.carrier], payload)
        return tuple(bodies)

    @cached_property
    def friction(self):
        """The joints' friction (see ``friction``), or None when all of it is zero."""
        if not any(j.friction.viscous or j.friction.coulomb for j in self.joints):
            return None
        return JointFriction.of(self)

    def with_payload(self, payload: RigidBody) -> RobotModel:
        return replace(self, payload=payload)

    def with_gravity(self, gravity) -> RobotModel:
        return replace(self, gravity=tuple(gravity))

    # -- flat parameter form --------------------------------------------------------

    def to_params(self) -> dict[str, Any]:
        params: dict[str, Any] = {
            "joint_names": list(self.joint_names),
            "gravity": list(self.gravity),
            "friction.smoothing_velocity": self.smoothing_velocity,
        }
        if not self.flange.is_identity:
            params["flange"] = self.flange.flat()
        if not self.is_chain:
            params.update(tree_params(self))
        if self.flange_joint is not None:
            params["flange_joint"] = self.flange_joint
        params.update(_body_params("payload", self.payload))
        for j in self.joints:
            key = param_prefix(j.name)
            if j.prismatic:
                params[f"{key}.type"] = j.kind
            if j.dh is not None:
                params[f"{key}.dh"] = [j.dh.a, j.dh.alpha, j.dh.d, j.dh.theta_offset]
            else:
                params[f"{key}.origin"] = j.origin.flat()
                params[f"{key}.axis"] = list(j.axis)
            params.update(_body_params(f"{key}.link", j.link))
            if not j.physical:
                params[f"{key}.link.physical"] = False
            params[f"{key}.position_limits"] = list(j.position_limits)
            params[f"{key}.torque_limit"] = j.torque_limit
            params[f"{key}.velocity_limit"] = j.velocity_limit
            params[f"{key}.acceleration_limit"] = j.acceleration_limit
            params[f"{key}.friction.viscous"] = j.friction.viscous
            params[f"{key}.friction.coulomb"] = j.friction.coulomb
            params[f"{key}.armature"] = j.armature
        return params

    @classmethod
    def from_params(cls, params: Mapping[str, Any]) -> RobotModel:
        """Build from flat parameter names (as in ``to_params``); unknown names are ignored."""

        def get(name, default=None):
            if name in params and params[name] is not None:
                return params[name]
            if default is not None:
                return default
            raise ModelError(name, "missing")

        names = check_joint_names(get("joint_names"))
        parent = mimics = None
        if params.get("tree.joints") is not None:
            names, independent = check_joint_names(get("tree.joints")), names
            parent, mimics = tree_from_params(names, params, get)
            if [name for name, mimic in zip(names, mimics) if mimic is None] != independent:
                raise ModelError("joint_names", "must be tree.joints but the mimic joints, in that order")
        joints = tuple(_joint_from_params(name, params, get) for name in names)
        payload = _body_from_params("payload", get, optional=True)
        return cls(
            joints,
            finite_numbers("gravity", get("gravity"), 3),
            payload,
            Placement.validated("flange", get("flange", (0.0,) * 6)),
            get("friction.smoothing_velocity", DEFAULT_SMOOTHING_VELOCITY),
            parent,
            mimics,
            params.get("flange_joint") or None,
        )


# a joint's limits, friction and rotor inertia: what a URDF's model may take from a params file
JOINT_DRIVE_FIELDS = (
    "position_limits",
    "torque_limit",
    "velocity_limit",
    "acceleration_limit",
    "friction.viscous",
    "friction.coulomb",
    "armature",
)
JOINT_FIELDS = (
    "type",
    "link.physical",
    "dh",
    "origin",
    "axis",
    "link.mass",
    "link.com",
    "link.inertia",
    *JOINT_DRIVE_FIELDS,
)
JOINTS_KEPT = 256  # joints remembered by their parameter values
_joints_by_values: dict[tuple, Joint] = {}


def _joint_from_params(name: str, params: Mapping[str, Any], get) -> Joint:
    """The validated joint ``name``, validated once for the same values: a change of other
    parameters (the payload's) re-validates no joint. The values are told apart by their
    repr, exact for the numbers a valid joint has (and True, 1 and 1.0 differ, as 0.0 and -0.0)."""
    key = name, repr([params.get(f"{param_prefix(name)}.{field}") for field in JOINT_FIELDS])
    joint = _joints_by_values.get(key)
    if joint is None:
        joint = validated_joint(_raw_joint(name, params, get))
        if len(_joints_by_values) >= JOINTS_KEPT:
            _joints_by_values.clear()
        _joints_by_values[key] = joint
    return joint


def _raw_joint(joint_name: str, params: Mapping[str, Any], get) -> Joint:
    name = param_prefix(joint_name)
    kind = get(f"{name}.type", "revolute")
    if kind not in KINDS:
        raise ModelError(f"{name}.type", f"must be one of {', '.join(KINDS)}, got {kind!r}")
    physical = get(f"{name}.link.physical", True)
    if not isinstance(physical, bool):
        raise ModelError(f"{name}.link.physical", f"must be true or false, got {physical!r}")
    if params.get(f"{name}.dh") is None and params.get(f"{name}.origin") is not None:
        kinematics = dict(
            origin=Placement.validated(f"{name}.origin", get(f"{name}.origin")),
            axis=finite_numbers(f"{name}.axis", get(f"{name}.axis"), 3),
        )
    else:
        kinematics = dict(dh=DH(*finite_numbers(f"{name}.dh", get(f"{name}.dh"), 4)))
    return Joint(
        joint_name,
        kind=kind,
        physical=physical,
        link=_body_from_params(f"{name}.link", get, physical=physical),
        position_limits=finite_numbers(
            f"{name}.position_limits", get(f"{name}.position_limits", (-math.pi, math.pi)), 2
        ),
        torque_limit=get(f"{name}.torque_limit", 0.0),
        velocity_limit=get(f"{name}.velocity_limit", 0.0),
        acceleration_limit=get(f"{name}.acceleration_limit", 0.0),
        friction=Friction(get(f"{name}.friction.viscous", 0.0), get(f"{name}.friction.coulomb", 0.0)),
        armature=get(f"{name}.armature", 0.0),
        **kinematics,
    )


def check_joint_names(names) -> list[str]:
    """The names as a list, or ModelError: at least one, unique, printable, their parameter
    prefixes (see ``param_prefix``) unique."""
    if not isinstance(names, (list, tuple)) or not all(isinstance(x, str) for x in names):
        raise ModelError("joint_names", f"expected a list of names, got {names!r}")
    names = list(names)
    if not names:
        raise ModelError("joint_names", "at least one joint is needed")
    for name in names:
        if not name or len(name) > MAX_NAME or not name.isprintable():
            shown = repr(name[:MAX_NAME]) + ("..." if len(name) > MAX_NAME else "")
            raise ModelError("joint_names", f"{shown} is not a valid joint name (1 to {MAX_NAME} printable characters)")
    if len(set(names)) != len(names):
        raise ModelError("joint_names", f"names must be unique, got {_shown(names)}")
    prefixes = [param_prefix(name) for name in names]
    if len(set(prefixes)) != len(prefixes):
        twins = sorted({f"{a!r}" for a, p in zip(names, prefixes) if prefixes.count(p) > 1})
        raise ModelError("joint_names", f"{', '.join(twins)[:200]} share a parameter prefix (see param_prefix)")
    return names


def _shown(names: list[str]) -> str:
    text = ", ".join(names)
    return text if len(text) < 200 else text[:200] + f"... ({len(names)} names)"


def _body_params(prefix: str, body: RigidBody) -> dict[str, Any]:
    return {
        f"{prefix}.mass": body.mass,
        f"{prefix}.com": list(body.com),
        f"{prefix}.inertia": list(body.inertia),
    }


def _body_from_params(prefix: str, get, optional=False, physical=True) -> RigidBody:
    zeros = (0.0,) * 6 if optional else None
    return RigidBody.validated(
        prefix,
        get(f"{prefix}.mass", 0.0 if optional else None),
        get(f"{prefix}.com", ZERO3 if optional else None),
        get(f"{prefix}.inertia", zeros),
        physical=physical,
    )
