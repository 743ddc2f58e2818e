"""A Pinocchio model of a RobotModel, built from its DH rows and inertials alone.

Standard DH: A_i = Rot_z(q_i + theta_offset_i) Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i).
Joint i is a revolute joint about z placed at (body frame i-1) * Rot_z(theta_offset_i);
body frame i (DH frame i) sits at SE3(Rot_x(alpha_i), (a_i, 0, d_i)) in joint i's frame.
The payload is appended to the last joint as a body of its own (Pinocchio adds the
inertias), so the payload merge of our code is checked as well.
"""

import numpy as np
import pinocchio as pin


def rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def body_placement(dh) -> pin.SE3:
    """DH frame i in joint i's frame: Trans_z(d) Trans_x(a) Rot_x(alpha)."""
    return pin.SE3(rot_x(dh.alpha), np.array([dh.a, 0.0, dh.d]))


def spatial_inertia(body) -> pin.Inertia:
    """A RigidBody (mass, CoM, inertia about the CoM as Ixx Iyy Izz Ixy Ixz Iyz) for Pinocchio."""
    xx, yy, zz, xy, xz, yz = body.inertia
    about_com = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    return pin.Inertia(body.mass, np.array(body.com, dtype=float), about_com)


def build(robot) -> pin.Model:
    """The Pinocchio model of ``robot`` (a RobotModel): joint ids 1..n, gravity included."""
    model = pin.Model()
    model.gravity.linear = np.array(robot.gravity, dtype=float)
    parent, previous_body = 0, pin.SE3.Identity()
    for i, joint in enumerate(robot.joints):
        placement = previous_body * pin.SE3(rot_z(joint.dh.theta_offset), np.zeros(3))
        joint_id = model.addJoint(parent, pin.JointModelRZ(), placement, joint.name)
        previous_body = body_placement(joint.dh)
        model.appendBodyToJoint(joint_id, spatial_inertia(joint.link), previous_body)
        if i == robot.n - 1:
            model.appendBodyToJoint(joint_id, spatial_inertia(robot.payload), previous_body)
        parent = joint_id
    return model


def flange_fext(pin_model: pin.Model, robot, wrench) -> pin.StdVec_Force:
    """Pinocchio's fext for a flange wrench (force, moment about the flange origin) given in
    the flange frame: a force on the last joint, expressed in that joint's frame."""
    fext = pin.StdVec_Force()
    for _ in range(pin_model.njoints):
        fext.append(pin.Force.Zero())
    wrench = np.asarray(wrench, dtype=float)
    on_flange = pin.Force(wrench[:3], wrench[3:])
    fext[pin_model.njoints - 1] = body_placement(robot.joints[-1].dh).act(on_flange)
    return fext
