"""URDF test helpers: the public arms, Pinocchio's reading of a URDF, and random URDF text.

Pinocchio builds its model from the same text with its own parser (buildModelFromXML);
joints our loader holds at zero are locked there with buildReducedModel, and a payload is
appended as a body at the tip link's frame.
"""

import math

import numpy as np
import pinocchio as pin

from irb140_dynamics.core.io.urdf import load_urdf

from .common import random_body, random_rotation
from .paths import URDF_DATA
from .pinocchio_model import spatial_inertia

ARMS = {"ur5": ("ur5.urdf", "tool0"), "panda": ("panda.urdf", "panda_hand_tcp")}  # file, tip link


def arm_text(name: str) -> str:
    return (URDF_DATA / ARMS[name][0]).read_text()


def pinocchio_of(text: str, held=(), tip: str | None = None, payload=None, gravity=(0.0, 0.0, -9.81)) -> pin.Model:
    """Pinocchio's model of a URDF: ``held`` joints locked at zero, ``payload`` (a RigidBody in
    the ``tip`` link's frame) appended to the joint that moves the tip."""
    model = pin.buildModelFromXML(text)
    if held:
        model = pin.buildReducedModel(model, [model.getJointId(name) for name in held], pin.neutral(model))
    if payload is not None:
        frame = model.frames[model.getFrameId(tip)]
        model.appendBodyToJoint(frame.parentJoint, spatial_inertia(payload), frame.placement)
    model.gravity.linear = np.array(gravity, dtype=float)
    return model


def expected_gravity(text, tip, q, payload=None):
    """Pinocchio's gravity torques of the URDF (its extra joints locked at zero)."""
    held = load_urdf(text, tip_link=tip).held_joints
    pm = pinocchio_of(text, held, tip, payload)
    return pin.computeGeneralizedGravity(pm, pm.createData(), np.asarray(q, dtype=float))


def pinocchio_rnea(model: pin.Model, data, q, qd, qdd, smoothing: float) -> np.ndarray:
    """pin.rnea plus the joint friction it leaves out (the URDF's damping and friction)."""
    return pin.rnea(model, data, q, qd, qdd) + model.damping * qd + model.friction * np.tanh(qd / smoothing)


def full_mass_matrix(model: pin.Model, data, q) -> np.ndarray:
    upper = np.triu(pin.crba(model, data, q))
    return upper + np.triu(upper, 1).T


# -- random URDF text -----------------------------------------------------------------------


def _numbers(values) -> str:
    return " ".join(repr(float(x)) for x in values)


def _origin(rng, scale: float = 0.3) -> str:
    rpy = [
        float(rng.choice([0.0, math.pi / 2, -math.pi / 2])) if rng.random() < 0.4 else rng.uniform(-3, 3)
        for _ in range(3)
    ]
    return f'<origin xyz="{_numbers(rng.uniform(-scale, scale, 3))}" rpy="{_numbers(rpy)}"/>'


def _link(name: str, rng, massive: bool = True) -> str:
    if not massive:
        return f'<link name="{name}"/>'
    body = random_body(rng)
    xx, yy, zz, xy, xz, yz = (float(x) for x in body.inertia)
    # the inertia given in a turned frame: URDF's <inertial><origin rpy>
    return (
        f'<link name="{name}"><inertial>{_origin(rng)}<mass value="{float(body.mass)!r}"/>'
        f'<inertia ixx="{xx!r}" iyy="{yy!r}" izz="{zz!r}" ixy="{xy!r}" ixz="{xz!r}" iyz="{yz!r}"/>'
        "</inertial></link>"
    )


def _joint(name: str, kind: str, parent: str, child: str, rng, extra: str = "") -> str:
    axis = random_rotation(rng)[:, 0] if rng.random() < 0.5 else np.eye(3)[rng.integers(3)]
    limit = '<limit lower="-2.5" upper="2.5" effort="50" velocity="3"/>' if kind in ("revolute", "prismatic") else ""
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>{_origin(rng)}'
        f'<axis xyz="{_numbers(axis)}"/>{limit}{extra}</joint>'
    )


def random_urdf(rng, n: int) -> tuple[str, list[str]]:
    """A URDF of n moving joints (revolute or continuous, random origins and axes) with,
    between each two, a fixed joint to a body and a revolute side branch (held at zero);
    bodies fixed to the base; a fixed tip frame with a body beyond it. (text, held joints)."""
    parts = [
        '<robot name="random">',
        _link("base", rng),
        _link("base_plate", rng),
        _joint("plate", "fixed", "base", "base_plate", rng),
    ]
    held, parent = [], "base"
    for i in range(n):
        kind = "continuous" if i % 3 == 2 else "revolute"
        dynamics = f'<dynamics damping="{float(rng.uniform(0, 1))!r}" friction="{float(rng.uniform(0, 2))!r}"/>'
        parts += [_joint(f"j{i}", kind, parent, f"l{i}", rng, dynamics), _link(f"l{i}", rng, massive=i != 1)]
        parts += [_joint(f"f{i}", "fixed", f"l{i}", f"l{i}_fixed", rng), _link(f"l{i}_fixed", rng)]
        parts += [_joint(f"side{i}", "revolute", f"l{i}_fixed", f"side{i}", rng), _link(f"side{i}", rng)]
        held.append(f"side{i}")
        parent = f"l{i}_fixed"
    parts += [
        _joint("to_tip", "fixed", parent, "tip", rng),
        _link("tip", rng, massive=False),
        _joint("beyond", "fixed", "tip", "tool", rng),
        _link("tool", rng),
        "</robot>",
    ]
    return "\n".join(parts), held
