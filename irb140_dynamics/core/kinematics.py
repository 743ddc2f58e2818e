"""Forward kinematics: joint transforms, link frames, the flange pose and Jacobian.

Poses are 4x4 homogeneous transforms from the frame to the base frame 0, in metres. q is a
state as in ``states`` (n finite real numbers), else ValueError naming it.
"""

from __future__ import annotations

import math

import numpy as np

from irb140_dynamics.core.model.per_model import PerModel
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
    """The poses of the base and the link frames 0..n in the base frame, (n + 1, 4, 4); on a
    tree or with mimic joints, of the base and every joint's link (``model.joints``' order)."""
    q = state(q, model.n, "q")
    if model.mimics is not None:
        q = model.all_positions(q).tolist()
    frames = [np.eye(4)]
    for (pre, post, axis, offset, prismatic), q_i, parent in zip(_placements(model), q, model.parent):
        # as Joint.transform, its constant matrices kept with the model
        move = _slide(axis, q_i) if prismatic else _turn(axis, q_i + offset)
        frames.append(frames[parent + 1] @ (pre @ move @ post))
    return np.array(frames)


def _rodrigues(axis: np.ndarray, c, s):
    """The rows of Rot(axis, angle) from its cos c and sin s (floats, or arrays of them),
    as joints.axis_rotation."""
    x, y, z = axis.tolist()
    v = 1.0 - c
    return (
        (c + v * x * x, v * x * y - s * z, v * x * z + s * y),
        (v * x * y + s * z, c + v * y * y, v * y * z - s * x),
        (v * x * z - s * y, v * y * z + s * x, c + v * z * z),
    )


def _turn(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rot(axis, angle) as a 4x4 transform, on floats."""
    rows = _rodrigues(axis, math.cos(angle), math.sin(angle))
    return np.array([[*row, 0.0] for row in rows] + [[0.0, 0.0, 0.0, 1.0]])


def _slide(axis: np.ndarray, distance: float) -> np.ndarray:
    move = np.eye(4)
    move[:3, 3] = axis * distance
    return move


def _flange(model: RobotModel) -> np.ndarray:
    matrix = model.flange.matrix()
    matrix.setflags(write=False)  # shared by every caller
    return matrix


def _joint_placements(model: RobotModel) -> list[tuple]:
    return [
        (
            joint.pre.matrix(),
            joint.post.matrix(),
            np.asarray(joint.axis if joint.prismatic else joint.turning_axis, dtype=float),
            float(joint.offset),
            joint.prismatic,
        )
        for joint in model.joints
    ]


# The flange's placement on its link (the last one's, 4x4), and per joint (pre, post as 4x4, axis,
# offset, prismatic): made on first use and kept while the model lives (see per_model).
_FLANGES, _PLACEMENTS = PerModel(_flange), PerModel(_joint_placements)
_flange_matrix, _placements = _FLANGES.get, _PLACEMENTS.get


def flange_pose(model: RobotModel, q) -> np.ndarray:
    """The flange pose in the base frame, 4x4 (for DH models frame n)."""
    return link_frames(model, q)[model.carrier + 1] @ _flange_matrix(model)


def joint_origins(model: RobotModel, q) -> np.ndarray:
    """Where each joint's axis is placed, (n, 3) m in the base frame: the origin of joint i's
    frame (link frame i-1 placed by pre_i), which is URDF joint i's origin and URDF link i's."""
    return _origins(model, link_frames(model, q))


def joint_origins_and_flange(model: RobotModel, q) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``joint_origins``, ``flange_pose`` and ``flange_jacobian`` from one pass of forward
    kinematics."""
    frames = link_frames(model, q)
    pose = frames[model.carrier + 1] @ _flange_matrix(model)
    return _origins(model, frames), pose, _flange_jacobian(model, frames, pose)


def _origins(model: RobotModel, frames: np.ndarray) -> np.ndarray:
    """Each joint's origin (every joint of ``model.joints`` on a tree), from its parent's frame."""
    return np.array([(frames[p + 1] @ placed[0])[:3, 3] for p, placed in zip(model.parent, _placements(model))])


def flange_jacobian(model: RobotModel, q) -> np.ndarray:
    """The 6 x n geometric Jacobian of the flange, rows (v; w), in the base frame (a
    prismatic joint's column: its axis in v, zero in w)."""
    return _flange_jacobian(model, link_frames(model, q))


def flange_jacobians(model: RobotModel, Q) -> np.ndarray:
    """``flange_jacobian`` at each pose of Q (N, n): (N, 6, n), the same numbers; on a chain
    without mimic joints one pass of forward kinematics per joint over all the poses."""
    Q = np.asarray(Q, dtype=float)
    if Q.ndim != 2 or Q.shape[1] != model.n:
        raise ValueError(f"Q: expected poses shaped (N, {model.n}), got {Q.shape}")
    if model.mimics is not None or not model.is_chain:
        return np.array([flange_jacobian(model, q) for q in Q]).reshape(len(Q), 6, model.n)
    N = len(Q)
    frames = [np.broadcast_to(np.eye(4), (N, 4, 4))]
    for i, (pre, post, axis, offset, prismatic) in enumerate(_placements(model)):
        move = np.broadcast_to(np.eye(4), (N, 4, 4)).copy()
        if prismatic:
            move[:, :3, 3] = axis * Q[:, i, None]
        else:
            move[:] = _turns(axis, Q[:, i] + offset)
        frames.append(frames[-1] @ (pre @ move @ post))
    flange = (frames[model.carrier + 1] @ _flange_matrix(model))[:, :3, 3]
    J = np.empty((N, 6, model.n))
    for i, (frame, (pre, _, turning_axis, _, prismatic)) in enumerate(zip(frames[:-1], _placements(model))):
        joint_frame = frame @ pre
        axis, origin = joint_frame[:, :3, :3] @ turning_axis, joint_frame[:, :3, 3]
        if prismatic:
            J[:, :3, i], J[:, 3:, i] = axis, 0.0
            continue
        (ax, ay, az), (rx, ry, rz) = axis.T, (flange - origin).T
        J[:, :3, i] = np.stack([ay * rz - az * ry, az * rx - ax * rz, ax * ry - ay * rx], axis=1)
        J[:, 3:, i] = axis
    return J


def _turns(axis: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """``_turn`` of each angle (N,): (N, 4, 4), cos and sin by the math module as there."""
    c = np.array([math.cos(a) for a in angles.tolist()])
    s = np.array([math.sin(a) for a in angles.tolist()])
    M = np.zeros((len(angles), 4, 4))
    M[:, :3, :3] = np.stack([np.stack(row, axis=-1) for row in _rodrigues(axis, c, s)], axis=-2)
    M[:, 3, 3] = 1.0
    return M


def flange_pose_and_jacobian(model: RobotModel, q) -> tuple[np.ndarray, np.ndarray]:
    """``flange_pose`` and ``flange_jacobian`` from one pass of forward kinematics."""
    frames = link_frames(model, q)
    pose = frames[model.carrier + 1] @ _flange_matrix(model)
    return pose, _flange_jacobian(model, frames, pose)


def link_pose(model: RobotModel, q, joint: str) -> np.ndarray:
    """The pose of the link ``joint`` moves (its frame) in the base frame, 4x4."""
    return link_frames(model, q)[_joint_index(model, joint) + 1]


def link_jacobian(model: RobotModel, q, joint: str) -> np.ndarray:
    """The 6 x n geometric Jacobian of the origin of the link ``joint`` moves, rows (v; w)
    in the base frame: the columns of the joints it hangs from (a mimic joint's added to
    its joint's, times its multiplier), zero for the others."""
    frames = link_frames(model, q)
    index = _joint_index(model, joint)
    return _jacobian(model, frames, frames[index + 1][:3, 3], index)


def placed_pose_and_jacobian(model: RobotModel, q, joint: str, placement) -> tuple[np.ndarray, np.ndarray]:
    """The pose (4x4, base frame) of the frame ``placement`` (a ``Placement``) places in the
    link ``joint`` moves, and the 6 x n Jacobian of its origin (rows v; w, base axes)."""
    frames = link_frames(model, q)
    index = _joint_index(model, joint)
    pose = frames[index + 1] @ placement.matrix()
    return pose, _jacobian(model, frames, pose[:3, 3], index)


def _joint_index(model: RobotModel, joint: str) -> int:
    for i, j in enumerate(model.joints):
        if j.name == joint:
            return i
    raise ValueError(f"joint: no joint {str(joint)[:80]!r} in the model")


def _flange_jacobian(model: RobotModel, frames: np.ndarray, pose: np.ndarray | None = None) -> np.ndarray:
    flange = (frames[model.carrier + 1] @ _flange_matrix(model) if pose is None else pose)[:3, 3]
    if not model.is_chain:
        return _jacobian(model, frames, flange, model.carrier)
    J = np.empty((6, model.n))
    for i, (frame, (pre, _, turning_axis, _, prismatic)) in enumerate(zip(frames[:-1], _placements(model))):
        joint_frame = frame @ pre  # joint i+1's axis passes through its origin
        axis, origin = joint_frame[:3, :3] @ turning_axis, joint_frame[:3, 3]
        if prismatic:  # sliding: the flange moves along the axis, does not turn
            J[:3, i], J[3:, i] = axis, 0.0
            continue
        (ax, ay, az), (rx, ry, rz) = axis.tolist(), (flange - origin).tolist()
        J[:3, i] = (ay * rz - az * ry, az * rx - ax * rz, ax * ry - ay * rx)  # axis x r (np.cross: 10x slower)
        J[3:, i] = axis
    return J


def flange_motion(model: RobotModel, q, qd, qdd) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(pose, w, alpha, a): the flange's pose (4x4), angular velocity [rad/s], angular
    acceleration [rad/s^2] and its origin's linear acceleration [m/s^2], in the base frame,
    at (q, qd, qdd). Forward recursion from the base at rest, each joint's axis carried by
    the links before it: w_i = w + z qd_i, alpha_i = alpha + z qdd_i + w x z qd_i (turning;
    the acceleration of a point on the axis unchanged), a_i = a + z qdd_i + 2 w x z qd_i
    (sliding), a point moved along a link by r: a + alpha x r + w x (w x r). A chain only
    (ValueError for a tree or mimic joints)."""
    if not model.is_chain:
        raise ValueError("flange_motion: a chain with its flange on the last joint only")
    qd, qdd = state(qd, model.n, "qd"), state(qdd, model.n, "qdd")
    frames = link_frames(model, q)
    placements = _placements(model)
    joint_frames = frames[:-1] @ np.array([pre for pre, *_ in placements])  # one batched product
    axes = np.einsum("nij,nj->ni", joint_frames[:, :3, :3], np.array([p[2] for p in placements])).tolist()
    w, alpha, a, point = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    for z, origin, (*_, prismatic), qd_i, qdd_i in zip(axes, joint_frames[:, :3, 3].tolist(), placements, qd, qdd):
        a = _carried(a, w, alpha, _minus(origin, point))
        point = origin
        w_z = _cross(w, z)
        if prismatic:
            a = tuple(a_k + z_k * qdd_i + 2.0 * c_k * qd_i for a_k, z_k, c_k in zip(a, z, w_z))
        else:
            alpha = tuple(al_k + z_k * qdd_i + c_k * qd_i for al_k, z_k, c_k in zip(alpha, z, w_z))
            w = tuple(w_k + z_k * qd_i for w_k, z_k in zip(w, z))
    pose = frames[-1] @ _flange_matrix(model)
    a = _carried(a, w, alpha, _minus(pose[:3, 3].tolist(), point))
    return pose, np.array(w), np.array(alpha), np.array(a)


def _carried(a, w, alpha, r) -> tuple:
    """The acceleration of a point r further along a rigid body whose point has acceleration a."""
    return tuple(map(sum, zip(a, _cross(alpha, r), _cross(w, _cross(w, r)))))


def _cross(u, v) -> tuple:
    (ux, uy, uz), (vx, vy, vz) = u, v
    return (uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)


def _minus(u, v) -> tuple:
    return tuple(x - y for x, y in zip(u, v))


def _jacobian(model: RobotModel, frames: np.ndarray, point: np.ndarray, link: int) -> np.ndarray:
    """The 6 x n Jacobian of ``point`` (base frame) fixed to joint ``link``'s link, on a tree
    and with mimic joints: the link's ancestors' columns, the others zero."""
    J = np.zeros((6, model.n))
    placements, coordinates = _placements(model), model.coordinates
    i = link
    while i >= 0:
        pre, _, turning_axis, _, prismatic = placements[i]
        joint_frame = frames[model.parent[i] + 1] @ pre
        axis, origin = joint_frame[:3, :3] @ turning_axis, joint_frame[:3, 3]
        k, multiplier, _ = coordinates[i]
        if prismatic:
            J[:3, k] += multiplier * axis
        else:
            J[:3, k] += multiplier * np.cross(axis, point - origin)
            J[3:, k] += multiplier * axis
        i = model.parent[i]
    return J
