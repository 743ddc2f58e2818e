"""A URDF's chain from base_link to tip_link as a RobotModel.

- The chain's revolute and continuous joints become the model's joints, in URDF form
  (origin, axis; link frames are the URDF's child links' frames), named as in the URDF.
- Fixed joints are merged: a body fixed to a moving link is lumped into it (inertial
  moved and turned into the link's frame), and the fixed joints between two moving
  joints make up the next one's origin. Fixed joints after the last moving joint up to
  tip_link give the model's ``flange`` (the tip_link frame, where the payload sits).
- Joints hanging off the chain (a gripper's fingers) are held at zero: their bodies are
  lumped into the chain link they hang from, and their names are returned.
- Bodies that do not move (base_link, what is fixed to it, what is above it) are left out.
- <limit lower upper> are the position limits (continuous joints: CONTINUOUS_LIMITS),
  ``effort`` the torque limit, ``velocity`` the velocity limit (0 or absent: none);
  <dynamics damping friction> are viscous and Coulomb friction.
- Refused, with UrdfError naming the element: prismatic, floating and planar joints and
  mimic joints in the chain; a revolute joint without <limit>; a moving link without
  <inertial> when nothing it carries has mass; besides everything ``tree`` refuses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import reduce

import numpy as np

from irb140_dynamics.core.io.urdf.tree import UrdfError, UrdfJoint, UrdfTree, number, parse_tree
from irb140_dynamics.core.model.joints import Friction, Joint, Placement, matrix_rpy
from irb140_dynamics.core.model.rigid_body import ModelError, RigidBody, combine, placed
from irb140_dynamics.core.model.robot_model import RobotModel

MOVING = ("revolute", "continuous")
CONTINUOUS_LIMITS = (-4 * math.pi, 4 * math.pi)  # rad: two turns either way, every angle within


@dataclass(frozen=True)
class LoadedUrdf:
    """The model of a URDF's chain and how it was read."""

    model: RobotModel
    base_link: str
    tip_link: str
    held_joints: tuple[str, ...]  # moving joints off the chain, held at zero, bodies lumped
    robot_name: str = ""  # <robot name="...">: the hardware_id of the nodes' /diagnostics


def load_urdf(text: str, base_link: str | None = None, tip_link: str | None = None) -> LoadedUrdf:
    """The chain from ``base_link`` (default: the root link) to ``tip_link`` (default: the
    only leaf below base_link) as a RobotModel (gravity and payload: the defaults)."""
    tree = parse_tree(text)
    base, tip, path = tree.chain(base_link, tip_link)
    for joint in path:
        if joint.kind not in ("fixed", *MOVING):
            raise UrdfError(
                joint.label,
                f"a {joint.kind} joint in the chain from {base!r} to {tip!r}: only "
                "revolute, continuous and fixed joints are supported there",
            )
        if joint.element.find("mimic") is not None:
            raise UrdfError(f"{joint.label} <mimic>", "a mimic joint in the chain is not supported")
    moving = [joint for joint in path if joint.kind in MOVING]
    if not moving:
        raise UrdfError("chain", f"no revolute or continuous joint from {base!r} to {tip!r}")

    origins, since_last = [], Placement()
    for joint in path:
        if joint.kind == "fixed":
            since_last = compose(since_last, joint.origin)
        else:
            origins.append(compose(since_last, joint.origin))
            since_last = Placement()
    held: list[str] = []
    bodies = [
        lumped(tree, joint.child, moving[k + 1].name if k + 1 < len(moving) else None, held)
        for k, joint in enumerate(moving)
    ]
    for k, (joint, (_, has_inertial)) in enumerate(zip(moving, bodies)):
        if not has_inertial and sum(body.mass for body, _ in bodies[k:]) == 0.0:
            raise UrdfError(
                f'link "{joint.child}"',
                f'moved by joint "{joint.name}": no <inertial>, and nothing it carries has mass',
            )
    joints = [_joint(joint, placement, body) for joint, placement, (body, _) in zip(moving, origins, bodies)]
    try:
        model = RobotModel(tuple(joints), flange=since_last)
    except ModelError as error:
        raise UrdfError("chain", str(error)) from None
    return LoadedUrdf(model, base, tip, tuple(held), tree.name)


def compose(a: Placement, b: Placement) -> Placement:
    """The placement a * b; exact when either is a pure translation or the identity."""
    if a.is_identity:
        return b
    if b.is_identity:
        return a
    xyz = tuple((np.array(a.xyz) + a.rotation() @ np.array(b.xyz)).tolist())
    if b.rpy == (0.0, 0.0, 0.0):
        return Placement(xyz, a.rpy)
    if a.rpy == (0.0, 0.0, 0.0):
        return Placement(xyz, b.rpy)
    return Placement(xyz, matrix_rpy(a.rotation() @ b.rotation()))


def lumped(tree: UrdfTree, link: str, stop: str | None, held: list[str]) -> tuple[RigidBody, bool]:
    """Everything rigidly attached to ``link`` (joints off the chain at zero), up to the
    chain joint ``stop``, as one body in ``link``'s frame; and whether any had an inertial."""
    bodies, stack = [], [(link, np.eye(4))]
    while stack:
        name, T = stack.pop()
        if tree.inertials[name] is not None:
            bodies.append(placed(tree.inertials[name], T[:3, :3], T[:3, 3]) if name != link else tree.inertials[name])
        for joint in tree.child_joints[name]:
            if joint.name == stop:
                continue
            if joint.kind != "fixed":
                held.append(joint.name)
            stack.append((joint.child, T @ joint.origin.matrix()))
    return (reduce(combine, bodies) if bodies else RigidBody()), bool(bodies)


def _joint(joint: UrdfJoint, origin: Placement, body: RigidBody) -> Joint:
    where = f"{joint.label} <limit>"
    limit = joint.element.find("limit")
    if limit is None and joint.kind == "revolute":
        raise UrdfError(joint.label, "a revolute joint needs <limit lower upper effort velocity>")
    if joint.kind == "continuous":
        lower, upper = CONTINUOUS_LIMITS
    else:
        lower, upper = number(limit, "lower", where, 0.0), number(limit, "upper", where, 0.0)
        if lower > upper:
            raise UrdfError(where, f"lower {lower} > upper {upper}")
    effort, velocity = number(limit, "effort", where, 0.0), number(limit, "velocity", where, 0.0)
    dynamics = joint.element.find("dynamics")
    damping = number(dynamics, "damping", f"{joint.label} <dynamics>", 0.0)
    friction = number(dynamics, "friction", f"{joint.label} <dynamics>", 0.0)
    for what, value, element in (
        ("effort", effort, "limit"),
        ("velocity", velocity, "limit"),
        ("damping", damping, "dynamics"),
        ("friction", friction, "dynamics"),
    ):
        if value < 0.0:
            raise UrdfError(f"{joint.label} <{element}>", f"{what} must be >= 0, got {value}")
    return Joint(
        joint.name,
        link=body,
        position_limits=(lower, upper),
        torque_limit=effort,
        origin=origin,
        axis=joint.axis,
        velocity_limit=velocity,
        friction=Friction(damping, friction),
    )
