"""A RobotModel as MuJoCo's model format (MJCF text), generated from the model directly.

One body per link, its frame the link frame i, nested along ``model.parent`` (a tree: the
bodies of two arms in the body of their torso). Body i sits in its parent's at its zero-pose
placement pre_i * Rot(axis_i, offset_i) * post_i; its hinge turns it by
post_i^-1 * Rot(axis_i, q_i) * post_i, i.e. about the axis R_post^T axis_i through the
point -R_post^T t_post (the joint frame's origin) in body i's frame. Then
T_i(q) = pre Rot(axis, offset) post * post^-1 Rot(axis, q) post = pre Rot(axis, q + offset) post
and MuJoCo's qpos is our q. A prismatic joint (URDF form: post is the identity) is a slide
joint along its axis: T_i(q) = pre Trans(axis q). Each body carries its link's inertial (mass, CoM, full inertia
about the CoM in the link frame); the payload is a body welded to the last link at
``flange``. Joint extras: ``armature`` (added to M's diagonal, as ours), viscous friction as
``damping`` (MuJoCo's passive force -damping qd, as our viscous term), Coulomb friction as
``frictionloss`` (MuJoCo's dry friction, a constraint that holds a joint still up to the
level: realistic for a true arm, but not our tanh smoothing; made as stiff as MuJoCo allows,
time constant 2 timesteps and impedance 0.999..0.9999, so that a joint held at 2/3 of its
level creeps by about 0.5 mrad/s instead of the 0.5 rad/s of MuJoCo's defaults), position
limits as ``range`` (soft constraints: stops, MuJoCo's default stiffness). A mimic joint is
a joint of its own held to its joint by an equality constraint (``<equality><joint
polycoef>``, as stiff as the friction's): MuJoCo's qpos holds every joint of
``model.joints``, the state's q its independent ones (``engine`` maps them).

Massless links (the IRB-140's links 3 and 5): MuJoCo refuses a body with a joint and no mass
or inertia. The compiler's ``boundmass`` and ``boundinertia`` raise every body's mass and
principal moments to at least MINIMAL_INERTIA (1e-12 kg, kg m^2), leaving every body
already above it unchanged. On the IRB-140 that changes torques by ~1e-11 N m, three
orders below the 1e-8 N m the cross-check tests hold MuJoCo to.
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import mujoco
import numpy as np

from irb140_dynamics.core.model.rigid_body import RigidBody
from irb140_dynamics.core.model.robot_model import RobotModel

MINIMAL_INERTIA = 1e-12  # kg and kg m^2: lower bound of each body's mass and principal moments
FRICTION_IMPEDANCE = (0.999, 0.9999, 0.001, 0.5, 2.0)  # solimpfriction: dry friction nearly hard
INTEGRATORS = ("implicitfast", "RK4", "implicit", "Euler")
MIMIC_STEPS = 2.0  # a mimic joint's equality: its time constant in timesteps (MuJoCo's stiffest stable)
MIMIC_IMPEDANCE = (0.999, 0.9999, 0.001, 0.5, 2.0)  # solimp: the equality nearly hard


def mjcf(
    model: RobotModel,
    timestep: float = 0.001,
    integrator: str = "implicitfast",
    friction: bool = True,
    limits: bool = True,
    name: str = "arm",
) -> str:
    """The MJCF document of ``model``.

    ``friction`` False: no damping and no frictionloss (for cross-checks against the
    frictionless dynamics); ``limits`` False: no joint ranges.
    """
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator: must be one of {', '.join(INTEGRATORS)}; got {integrator!r}")
    if not timestep > 0.0:
        raise ValueError(f"timestep: must be > 0, got {timestep}")
    lines = [
        f"<mujoco model={quoteattr(name)}>",
        f'  <compiler angle="radian" boundmass="{MINIMAL_INERTIA:g}" boundinertia="{MINIMAL_INERTIA:g}"/>',
        f'  <option timestep="{_number(timestep)}" integrator="{integrator}" gravity="{_numbers(model.gravity)}">',
        '    <flag contact="disable"/>',
        "  </option>",
        "  <worldbody>",
    ]
    below = [[] for _ in model.joints]
    for i, parent in enumerate(model.parent):
        if parent >= 0:
            below[parent].append(i)
    last = model.carrier  # the payload's link
    # depth first along model.parent: ("open", i) writes body i, ("close", i) ends it
    stack = [("open", i) for i, parent in reversed(list(enumerate(model.parent))) if parent < 0]
    indent = "    "
    while stack:
        action, i = stack.pop()
        if action == "close":
            indent = indent[:-2]
            lines.append(f"{indent}</body>")
            continue
        joint = model.joints[i]
        zero_pose = joint.transform(0.0)
        post = joint.post.matrix()
        R_post, t_post = post[:3, :3], post[:3, 3]
        lines.append(f"{indent}<body name={quoteattr(joint.name)} {_placement(zero_pose)}>")
        indent += "  "
        attributes = {
            "name": joint.name,
            "type": "slide" if joint.prismatic else "hinge",
            "pos": _numbers(-R_post.T @ t_post),
            "axis": _numbers(R_post.T @ np.array(joint.turning_axis)),
            "armature": _number(joint.armature),
        }
        if friction:
            attributes["damping"] = _number(joint.friction.viscous)
            attributes["frictionloss"] = _number(joint.friction.coulomb)
            attributes["solreffriction"] = _numbers((2.0 * timestep, 1.0))
            attributes["solimpfriction"] = _numbers(FRICTION_IMPEDANCE)
        if limits:
            attributes["limited"] = "true"
            attributes["range"] = _numbers(joint.position_limits)
        lines.append(f"{indent}<joint {' '.join(f'{k}={quoteattr(v)}' for k, v in attributes.items())}/>")
        if joint.link.mass > 0.0:
            lines.append(f"{indent}{_inertial(joint.link)}")
        if i == last and model.payload.mass > 0.0:
            lines.append(f"{indent}<body {_placement(model.flange.matrix())}>")  # unnamed: no clash with a link
            lines.append(f"{indent}  {_inertial(model.payload)}")
            lines.append(f"{indent}</body>")
        stack.append(("close", i))
        stack += [("open", child) for child in reversed(below[i])]
    lines.append("  </worldbody>")
    lines += _mimic_equalities(model, timestep)
    lines += ["</mujoco>", ""]
    return "\n".join(lines)


def _mimic_equalities(model: RobotModel, timestep: float) -> list[str]:
    """Each mimic joint held at multiplier * q_joint + offset by a joint equality (MuJoCo's
    polycoef: joint1 = c0 + c1 joint2), as stiff as MuJoCo steps stably: time constant
    MIMIC_STEPS timesteps, critically damped, impedance MIMIC_IMPEDANCE."""
    if model.mimics is None:
        return []
    solref = _numbers((MIMIC_STEPS * timestep, 1.0))
    lines = ["  <equality>"]
    for joint, mimic in zip(model.joints, model.mimics):
        if mimic is not None:
            attributes = {
                "joint1": joint.name,
                "joint2": mimic.joint,
                "polycoef": _numbers((mimic.offset, mimic.multiplier, 0.0, 0.0, 0.0)),
                "solref": solref,
                "solimp": _numbers(MIMIC_IMPEDANCE),
            }
            lines.append(f"    <joint {' '.join(f'{k}={quoteattr(v)}' for k, v in attributes.items())}/>")
    return [*lines, "  </equality>"]


def mujoco_model(model: RobotModel, **options) -> mujoco.MjModel:
    """The compiled MuJoCo model of ``model`` (options as ``mjcf``)."""
    return mujoco.MjModel.from_xml_string(mjcf(model, **options))


def _placement(T: np.ndarray) -> str:
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(T[:3, :3]).ravel())
    return f'pos="{_numbers(T[:3, 3])}" quat="{_numbers(quat)}"'


def _inertial(body: RigidBody) -> str:
    xx, yy, zz, *products = body.inertia
    # A diagonal inertia as diaginertia: older MuJoCo releases refuse a singular fullinertia
    # (a point mass, a payload given by its mass alone) but takes zeros there.
    if any(products):
        inertia = f'fullinertia="{_numbers(body.inertia)}"'
    else:
        inertia = f'diaginertia="{_numbers((xx, yy, zz))}"'
    return f'<inertial pos="{_numbers(body.com)}" mass="{_number(body.mass)}" {inertia}/>'


def _number(x: float) -> str:
    return repr(float(x))  # shortest text that reads back as the same double


def _numbers(xs) -> str:
    return " ".join(_number(x) for x in xs)
