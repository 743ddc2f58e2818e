"""The parameter regressor: torques linear in the dynamic parameters, tau = Y(q, qd, qdd) pi.

pi holds 13 numbers per joint, in two blocks:

    pi[10 i : 10 i + 10]       link i's inertial parameters, in Pinocchio's order and frame:
                               [m, m c_x, m c_y, m c_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz], the
                               first moment and the inertia about the origin of joint i's
                               frame, in that frame (for URDF joints the link frame; for DH
                               rows frame i-1 turned by theta_i: where Pinocchio puts joint i)
    pi[10 n + 3 i : + 3]       joint i's [viscous, coulomb, armature]

so Y[:, :10 n] is ``pinocchio.computeJointTorqueRegressor``. The friction columns are qd_i
and tanh(qd_i / v_s) (the smoothed Coulomb shape, see ``friction``), the armature's qdd_i.
The rigid-body part is generated code (see ``codegen``), like the other kernels.

With mimic joints, i runs over every joint of ``model.joints`` (n_all of them, mimic joints
included: each moves a link of its own) and Y's n rows are the independent joints': Y =
G^T Y_all(q_all, qd_all, qdd_all), as ``rnea`` carries a mimic joint's torque (virtual work,
``RobotModel.mimic_matrix``). A mimic joint of multiplier m following q_k gives row k
m^2 qd_k, tanh(qd_k / v_s) and m^2 qdd_k; its Coulomb column is zero unless |m| = 1 (the
only multipliers the model takes Coulomb friction with, see ``model.tree``).
"""

from __future__ import annotations

import numpy as np

from irb140_dynamics.core.algorithms.regressor import (  # noqa: F401 (part of this module's interface)
    INERTIAL_PARAMETERS,
    rigid_body_regressor,
)
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.core.model.joints import Friction
from irb140_dynamics.core.model.rigid_body import ModelError, RigidBody, inertia_entries, inertia_matrix
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.model.states import states

_CHUNK = 4096  # states per pass of the kernel (its buffers then stay in the CPU caches)

LINK_PARAMETERS = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
JOINT_PARAMETERS = ("viscous", "coulomb", "armature")
# pi's layout (the module's docstring): INERTIAL_PARAMETERS per link, then JOINT_TERMS per joint
JOINT_TERMS = len(JOINT_PARAMETERS)
PARAMETERS_PER_JOINT = INERTIAL_PARAMETERS + JOINT_TERMS

# -- public functions ---------------------------------------------------------------------


def parameter_count(model: RobotModel) -> int:
    """The length of pi: 13 per joint of ``model.joints`` (mimic joints included)."""
    return PARAMETERS_PER_JOINT * len(model.joints)


def zero_parameters(model: RobotModel) -> np.ndarray:
    """The indices of pi that every model of this structure holds at zero: the Coulomb
    friction of a mimic joint whose multiplier is not +-1 (its column is zero)."""
    links = len(model.joints)
    return np.array(
        [
            INERTIAL_PARAMETERS * links + JOINT_TERMS * i + 1
            for i, (_, m, _) in enumerate(model.coordinates)
            if abs(m) != 1.0
        ],
        dtype=int,
    )


def regressor(model: RobotModel, q, qd, qdd) -> np.ndarray:
    """Y(q, qd, qdd), n x 13 n_all: rnea(model, q, qd, qdd) == Y @ inertial_parameters(model)."""
    return regressor_batch(model, [q], [qd], [qdd])[0]


def regressor_batch(model: RobotModel, Q, QD, QDD) -> np.ndarray:
    """regressor for N states: (N, n) arrays -> Y shaped (N, n, 13 n_all)."""
    n, links = model.n, len(model.joints)
    q, qd, qdd = states(n, Q=Q, QD=QD, QDD=QDD)
    N = q.shape[1]
    # Y is a view of rows[entry, state]: the kernel writes each of its outputs (a row of N
    # states) whole and contiguously (a (N, n, 13n) array filled entry by entry would be
    # written with a stride of 13 n^2 numbers, four times slower). Output c * n + i is
    # Y[:, i, c]; the constant zeros (about half: link k moves no joint after k) are left
    # as they are, their pages never touched.
    width = parameter_count(model)
    rows = np.zeros((n * width, N))
    kernel = kernels_of(model).regressor
    where = [(j, (j % n) * width + j // n) for j in kernel.written]
    out = [None] * (INERTIAL_PARAMETERS * links * n)
    for start in range(0, N, _CHUNK):
        chunk = slice(start, start + _CHUNK)
        for j, row in where:
            out[j] = rows[row, chunk]
        kernel.into(out, q[:, chunk], qd[:, chunk], qdd[:, chunk])
    coulomb_shape = np.tanh(qd / model.smoothing_velocity)
    for i, (k, m, _) in enumerate(model.coordinates):  # joint i's terms, carried by coordinate k
        column = k * width + INERTIAL_PARAMETERS * links + JOINT_TERMS * i
        rows[column] = m * m * qd[k]
        rows[column + 1] = coulomb_shape[k] if abs(m) == 1.0 else 0.0
        rows[column + 2] = m * m * qdd[k]
    return rows.T.reshape(N, n, width)


def parameter_names(model: RobotModel) -> list[str]:
    """The names of pi's entries, e.g. 'joint_2.mcx', 'joint_2.viscous'."""
    names = [f"{j.name}.{p}" for j in model.joints for p in LINK_PARAMETERS]
    return names + [f"{j.name}.{p}" for j in model.joints for p in JOINT_PARAMETERS]


def inertial_parameters(model: RobotModel) -> np.ndarray:
    """pi of the model (13 n_all,), the payload merged into the flange's link."""
    links = [body_parameters(body, joint.post) for joint, body in zip(model.joints, model.bodies)]
    joints = [(j.friction.viscous, j.friction.coulomb, j.armature) for j in model.joints]
    return np.concatenate([np.ravel(links), np.ravel(joints)])


def with_inertial_parameters(model: RobotModel, pi) -> RobotModel:
    """The model with the links, friction and armature of pi (and no payload: pi's last
    link carries it). ModelError naming the joint if pi is not physically consistent."""
    from dataclasses import replace

    n = len(model.joints)
    pi = np.asarray(pi, dtype=float)
    if pi.shape != (parameter_count(model),):
        raise ValueError(f"pi: expected {parameter_count(model)} parameters, got shape {pi.shape}")
    links = np.reshape(pi[: INERTIAL_PARAMETERS * n], (n, INERTIAL_PARAMETERS))
    terms = np.reshape(pi[INERTIAL_PARAMETERS * n :], (n, JOINT_TERMS))
    joints = []
    for joint, link_parameters, (viscous, coulomb, armature) in zip(model.joints, links, terms):
        link = parameters_body(f"{joint.name}.link", link_parameters, joint.post)
        joints.append(replace(joint, link=link, friction=Friction(viscous, coulomb), armature=armature))
    return replace(model, joints=tuple(joints), payload=RigidBody())


def body_parameters(body: RigidBody, post) -> np.ndarray:
    """A body given in the link frame as its 10 parameters in the joint frame (see above)."""
    R = post.rotation()
    c = R @ np.array(body.com) + np.array(post.xyz)
    I = R @ inertia_matrix(body.inertia) @ R.T + body.mass * (c @ c * np.eye(3) - np.outer(c, c))
    m = body.mass
    return np.array([m, *(m * c), I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]])


def parameters_body(field: str, pi10, post) -> RigidBody:
    """The body (link frame) of 10 parameters in the joint frame; ModelError if impossible."""
    m, hx, hy, hz, xx, xy, yy, xz, yz, zz = (float(x) for x in pi10)
    I = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    h = np.array([hx, hy, hz])
    if m <= 0.0:
        if m < 0.0 or np.any(h != 0.0):
            raise ModelError(f"{field}.mass", f"not physically consistent: m = {m}, m c = {h.tolist()}")
        c = np.zeros(3)
    else:
        c = h / m
    I_c = I - m * (c @ c * np.eye(3) - np.outer(c, c))
    R = post.rotation()
    com = R.T @ (c - np.array(post.xyz))
    return RigidBody.validated(field, m, tuple(com.tolist()), inertia_entries(R.T @ I_c @ R))
