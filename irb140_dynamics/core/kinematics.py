"""Forward kinematics: joint transforms, link frames, the flange pose and Jacobian.

Poses are 4x4 homogeneous transforms from the frame to the base frame 0, in metres. q is a
state as in ``states`` (n finite real numbers), else ValueError naming it.
"""

from __future__ import annotations

import math

import numpy as np

from irb140_dynamics.core.model.robot_model import DH, RobotModel
from irb140_dynamics.core.model.states import state


def dh_transform(dh: DH, q: float) -> np.ndarray:
    """A_i = Rot_z(q + theta_offset) Trans_z(d) Trans_x(a) Rot_x(alpha)."""
    theta = q + dh.theta_offset
    ct, st = math.cos(theta), math.sin(theta)
    ca, sa = math.cos(dh.alpha), math.sin(dh.alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, dh.a * ct],
            [st, ct * ca, -ct * sa, dh.a * st],
            [0.0, sa, ca, dh.d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def link_frames(model: RobotModel, q) -> np.ndarray:
    """The poses of the base and the link frames 0..n in the base frame, (n + 1, 4, 4)."""
    frames = [np.eye(4)]
    for joint, q_i in zip(model.joints, state(q, model.n, "q")):
        frames.append(frames[-1] @ joint.transform(float(q_i)))
    return np.array(frames)


def flange_pose(model: RobotModel, q) -> np.ndarray:
    """The flange pose in the base frame, 4x4 (for DH models frame n)."""
    return link_frames(model, q)[-1] @ model.flange.matrix()


def flange_jacobian(model: RobotModel, q) -> np.ndarray:
    """The 6 x n geometric Jacobian of the flange, rows (v; w), in the base frame (a
    prismatic joint's column: its axis in v, zero in w)."""
    frames = link_frames(model, q)
    flange = (frames[-1] @ model.flange.matrix())[:3, 3]
    J = np.empty((6, model.n))
    for i, (frame, joint) in enumerate(zip(frames[:-1], model.joints)):
        joint_frame = frame @ joint.pre.matrix()  # joint i+1's axis passes through its origin
        axis, origin = joint_frame[:3, :3] @ np.array(joint.turning_axis), joint_frame[:3, 3]
        if joint.prismatic:  # sliding: the flange moves along the axis, does not turn
            J[:3, i], J[3:, i] = axis, 0.0
            continue
        J[:3, i] = np.cross(axis, flange - origin)
        J[3:, i] = axis
    return J
