"""A Pinocchio model of a RobotModel, built from its joints' placements and inertials alone.

Joint i moves link i by pre * Rot(axis, q_i + offset_i) * post (DH: pre = identity, axis
z, post = Trans(a, 0, d) Rot_x(alpha)). Pinocchio's joint i is a revolute joint about the
axis placed at (link frame i-1) * pre * Rot(axis, offset_i); link frame i sits at post in
joint i's frame. The payload is appended to the last joint as a body of its own at
post * flange (Pinocchio adds the inertias), so the payload merge of our code is checked
as well. Armature goes to Pinocchio's model.armature; Pinocchio has no friction.
"""

import numpy as np
import pinocchio as pin


def rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def se3(placement) -> pin.SE3:
    return pin.SE3(placement.rotation(), np.array(placement.xyz, dtype=float))


def body_placement(joint) -> pin.SE3:
    """Link frame i in joint i's frame (DH: Trans_z(d) Trans_x(a) Rot_x(alpha))."""
    return se3(joint.post)


def spatial_inertia(body) -> pin.Inertia:
    """A RigidBody (mass, CoM, inertia about the CoM as Ixx Iyy Izz Ixy Ixz Iyz) for Pinocchio."""
    xx, yy, zz, xy, xz, yz = body.inertia
    about_com = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    return pin.Inertia(body.mass, np.array(body.com, dtype=float), about_com)


def build(robot) -> pin.Model:
    """The Pinocchio model of ``robot`` (a RobotModel, a chain or a tree without mimic
    joints): joint ids 1..n in ``robot.joints``' order, parents as ``robot.parent``, gravity
    included."""
    model = pin.Model()
    model.gravity.linear = np.array(robot.gravity, dtype=float)
    bodies = []  # each joint's link frame in its joint frame
    for i, (joint, parent) in enumerate(zip(robot.joints, robot.parent)):
        axis = np.array(joint.turning_axis, dtype=float)
        offset = pin.SE3(pin.AngleAxis(joint.offset, axis).matrix(), np.zeros(3))
        previous_body = bodies[parent] if parent >= 0 else pin.SE3.Identity()
        placement = previous_body * se3(joint.pre) * offset
        kind = pin.JointModelRZ() if tuple(axis) == (0.0, 0.0, 1.0) else pin.JointModelRevoluteUnaligned(axis)
        joint_id = model.addJoint(parent + 1, kind, placement, joint.name)
        model.armature[i] = joint.armature
        bodies.append(body_placement(joint))
        model.appendBodyToJoint(joint_id, spatial_inertia(joint.link), bodies[-1])
        if i == robot.carrier:  # the payload on the flange's link
            model.appendBodyToJoint(joint_id, spatial_inertia(robot.payload), bodies[-1] * se3(robot.flange))
    return model


def flange_fext(pin_model: pin.Model, robot, wrench) -> pin.StdVec_Force:
    """Pinocchio's fext for a flange wrench (force, moment about the flange origin) given in
    the flange frame: a force on the last joint, expressed in that joint's frame."""
    fext = pin.StdVec_Force()
    for _ in range(pin_model.njoints):
        fext.append(pin.Force.Zero())
    wrench = np.asarray(wrench, dtype=float)
    on_flange = pin.Force(wrench[:3], wrench[3:])
    fext[pin_model.njoints - 1] = (body_placement(robot.joints[-1]) * se3(robot.flange)).act(on_flange)
    return fext
