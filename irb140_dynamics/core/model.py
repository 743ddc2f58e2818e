"""The robot model: a serial chain of revolute joints given by standard DH rows.

Units (SI throughout): m, rad, kg, kg m^2, m/s^2, N m.

Standard DH: A_i = Rot_z(q_i + theta_offset_i) Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i).
Link i is the body moved by joint i; its frame is DH frame i. The flange is frame n.
Gravity is given in the base frame 0.

A model is immutable. Its flat parameter form (``to_params`` / ``from_params``) uses the
same names as the ROS parameters of the nodes, so that a validation error names the
parameter to fix:

    joint_names                 [name, ...]
    gravity                     [gx, gy, gz]
    payload.mass / .com / .inertia
    <joint>.dh                  [a, alpha, d, theta_offset]
    <joint>.link.mass / .com / .inertia
    <joint>.position_limits     [lower, upper]
    <joint>.torque_limit        N m, 0 = none given

Besides being finite, masses, lengths, inertias and gravity are within sanity caps (see
``rigid_body``) that keep every number the algorithms derive from them finite.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, Mapping

from .rigid_body import (
    MAX_GRAVITY,
    MAX_LENGTH,
    ZERO3,
    ModelError,
    RigidBody,
    capped,
    combine,
    finite_number,
    finite_numbers,
)

_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")


@dataclass(frozen=True)
class DH:
    """One standard DH row: a [m], alpha [rad], d [m], theta_offset [rad]."""

    a: float = 0.0
    alpha: float = 0.0
    d: float = 0.0
    theta_offset: float = 0.0


@dataclass(frozen=True)
class Joint:
    """A revolute joint, the link it moves, and its limits."""

    name: str
    dh: DH
    link: RigidBody = RigidBody()
    position_limits: tuple[float, float] = (-math.pi, math.pi)
    torque_limit: float = 0.0  # N m; 0 means none given


@dataclass(frozen=True)
class RobotModel:
    """A validated serial-chain model; raises ModelError naming the bad field."""

    joints: tuple[Joint, ...]
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    payload: RigidBody = field(default_factory=RigidBody)

    def __post_init__(self):
        object.__setattr__(self, "joints", tuple(_validated_joint(j) for j in self.joints))
        object.__setattr__(self, "gravity", finite_numbers("gravity", self.gravity, 3))
        capped("gravity", "|g|", math.hypot(*self.gravity), MAX_GRAVITY, "m/s^2")
        object.__setattr__(self, "payload", _validated_body("payload", self.payload))
        check_joint_names(self.joint_names)

    @property
    def n(self) -> int:
        return len(self.joints)

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    @property
    def torque_limits(self) -> tuple[float, ...]:
        return tuple(j.torque_limit for j in self.joints)

    @property
    def bodies(self) -> tuple[RigidBody, ...]:
        """The moving bodies, the payload merged into the last link."""
        bodies = [j.link for j in self.joints]
        bodies[-1] = combine(bodies[-1], self.payload)
        return tuple(bodies)

    def with_payload(self, payload: RigidBody) -> "RobotModel":
        return replace(self, payload=payload)

    def with_gravity(self, gravity) -> "RobotModel":
        return replace(self, gravity=tuple(gravity))

    @cached_property
    def kernels(self):
        """Generated straight-line code for this model's algorithms (see codegen)."""
        from .kernels import Kernels

        return Kernels(self)

    # -- flat parameter form --------------------------------------------------------

    def to_params(self) -> dict[str, Any]:
        params: dict[str, Any] = {
            "joint_names": list(self.joint_names),
            "gravity": list(self.gravity),
        }
        params.update(_body_params("payload", self.payload))
        for j in self.joints:
            params[f"{j.name}.dh"] = [j.dh.a, j.dh.alpha, j.dh.d, j.dh.theta_offset]
            params.update(_body_params(f"{j.name}.link", j.link))
            params[f"{j.name}.position_limits"] = list(j.position_limits)
            params[f"{j.name}.torque_limit"] = j.torque_limit
        return params

    @classmethod
    def from_params(cls, params: Mapping[str, Any]) -> "RobotModel":
        """Build from flat parameter names (as in ``to_params``); unknown names are ignored."""

        def get(name, default=None):
            if name in params and params[name] is not None:
                return params[name]
            if default is not None:
                return default
            raise ModelError(name, "missing")

        names = check_joint_names(get("joint_names"))
        joints = []
        for name in names:
            a, alpha, d, offset = finite_numbers(f"{name}.dh", get(f"{name}.dh"), 4)
            link = _body_from_params(f"{name}.link", get)
            joints.append(
                Joint(
                    name,
                    DH(a, alpha, d, offset),
                    link,
                    finite_numbers(f"{name}.position_limits", get(f"{name}.position_limits", (-math.pi, math.pi)), 2),
                    get(f"{name}.torque_limit", 0.0),
                )
            )
        payload = _body_from_params("payload", get, optional=True)
        return cls(tuple(joints), finite_numbers("gravity", get("gravity"), 3), payload)


def check_joint_names(names) -> list[str]:
    """The names as a list, or ModelError: at least one, unique, each usable as a parameter prefix."""
    if not isinstance(names, (list, tuple)) or not all(isinstance(x, str) for x in names):
        raise ModelError("joint_names", f"expected a list of names, got {names!r}")
    names = list(names)
    if not names:
        raise ModelError("joint_names", "at least one joint is needed")
    for name in names:
        if not _NAME.match(name):
            raise ModelError(
                "joint_names",
                f"{name!r} is not a valid joint name (letters, digits, '_'; starts with a letter)",
            )
    if len(set(names)) != len(names):
        raise ModelError("joint_names", f"names must be unique, got {names}")
    return names


def _validated_body(prefix: str, body: RigidBody) -> RigidBody:
    return RigidBody.validated(prefix, body.mass, body.com, body.inertia)


def _validated_joint(j: Joint) -> Joint:
    dh = DH(*finite_numbers(f"{j.name}.dh", (j.dh.a, j.dh.alpha, j.dh.d, j.dh.theta_offset), 4))
    capped(f"{j.name}.dh", "|a| and |d|", max(abs(dh.a), abs(dh.d)), MAX_LENGTH, "m")
    lower, upper = finite_numbers(f"{j.name}.position_limits", j.position_limits, 2)
    if lower > upper:
        raise ModelError(f"{j.name}.position_limits", f"lower {lower} > upper {upper}")
    limit = finite_number(f"{j.name}.torque_limit", j.torque_limit)
    if limit < 0.0:
        raise ModelError(f"{j.name}.torque_limit", f"must be >= 0 (0 = none), got {limit}")
    link = _validated_body(f"{j.name}.link", j.link)
    return Joint(j.name, dh, link, (lower, upper), limit)


def _body_params(prefix: str, body: RigidBody) -> dict[str, Any]:
    return {
        f"{prefix}.mass": body.mass,
        f"{prefix}.com": list(body.com),
        f"{prefix}.inertia": list(body.inertia),
    }


def _body_from_params(prefix: str, get, optional=False) -> RigidBody:
    zeros = (0.0,) * 6 if optional else None
    return RigidBody.validated(
        prefix,
        get(f"{prefix}.mass", 0.0 if optional else None),
        get(f"{prefix}.com", ZERO3 if optional else None),
        get(f"{prefix}.inertia", zeros),
    )


def read_parameter_file(path, node_name: str | None = None) -> dict[str, Any]:
    """The flat parameters of a ROS 2 parameter file (``/**`` merged with ``node_name``)."""
    import yaml

    with open(path) as stream:
        document = yaml.safe_load(stream) or {}
    params: dict[str, Any] = {}
    for key in ("/**", node_name, f"/{node_name}" if node_name else None):
        if key and key in document:
            _flatten(document[key].get("ros__parameters", {}), "", params)
    return params


def _flatten(tree: Mapping[str, Any], prefix: str, out: dict[str, Any]) -> None:
    for key, value in tree.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            _flatten(value, f"{name}.", out)
        else:
            out[name] = value


def load_model(path, node_name: str | None = None) -> RobotModel:
    """The model described by a ROS 2 parameter file."""
    return RobotModel.from_params(read_parameter_file(path, node_name))
