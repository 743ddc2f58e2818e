"""A wrist force/torque sensor's reading freed of its tool: the contact wrench.

Conventions (SI: N, N m, m, kg, kg m^2; rad/s, rad/s^2, m/s^2):

- the sensor sits on a link rigidly attached to the last moving link (the flange, the last
  link itself, or a fixed link between); its frame S in the flange frame is ``mount`` (4x4);
- the tool is everything beyond the sensor: the model's payload (mass m, CoM c and inertia
  I about the CoM, given in the flange frame);
- a reading w = (f; tau) is the wrench acting ON the sensor FROM the tool side, in S's axes,
  the torque about S's origin o: a tool hanging still reads its weight, f = m g;
- the contact wrench is the wrench the environment exerts ON the tool, about o:

      contact = w - bias - w_tool,
      w_tool = ( m (g - a_c);  (c - o) x m (g - a_c) - I alpha - w x I w )

  w_tool being what the tool alone loads the sensor with (its weight and its inertia, by
  Newton and Euler), a_c the CoM's acceleration, w and alpha the link's angular velocity
  and acceleration (core.kinematics.flange_motion), all at (q, qd, qdd).

The contact wrench is given in S's axes (``sensor``) or the base frame's (``base``); the
torque is about the sensor's origin in both.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from irb140_dynamics.core.kinematics import flange_motion
from irb140_dynamics.core.model.joints import Placement
from irb140_dynamics.core.model.rigid_body import inertia_matrix
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.model.states import state

FRAMES = ("sensor", "base")
NO_BIAS = np.zeros(6)


def sensor_mount(model: RobotModel, link: str, carried: Mapping[str, tuple[str, Placement]]) -> np.ndarray:
    """The sensor frame in the flange frame (4x4) when the sensor is on ``link``; ``carried``:
    the links the arm's joints move, link -> (joint, placement in its link frame)
    (``LoadedUrdf.carried``, or ``exported_carried`` for a model of parameters). ValueError
    naming ft_sensor.link for a link no joint moves, or one the flange's joint does not carry
    (the tool would be links), or on a model that is no plain chain (``flange_motion``'s: a
    tree, mimic joints, or the flange moved before the last joint by payload.link)."""
    if model.mimics is not None or any(p != i - 1 for i, p in enumerate(model.parent)):
        raise ValueError(
            "ft_sensor.link: a force/torque sensor needs an arm that is one chain (no tree, no mimic joint)"
        )
    if link not in carried:
        names = ", ".join(sorted(carried)[:12])
        raise ValueError(f"ft_sensor.link: no link {link[:80]!r} that the arm's joints move (links: {names})")
    joint, placement = carried[link]
    last = model.joints[model.carrier].name
    if joint != last:
        raise ValueError(
            f"ft_sensor.link: {link!r} is moved by joint {joint}, not by {last} that carries the flange: the "
            "sensor must be on the flange's link (the tool beyond it is the payload)"
        )
    if not model.is_chain:  # payload.link put the flange before the last joint
        raise ValueError(f"ft_sensor.link: {link!r} is before the last joint; the sensor must be on the last link")
    return _rigid_inverse(model.flange.matrix()) @ placement.matrix()


def tool_wrench(model: RobotModel, q, qd, qdd, mount: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(w_tool in the sensor's axes, the sensor's orientation R in the base frame): the
    wrench the tool alone loads the sensor with at (q, qd, qdd) (see the module)."""
    pose, w, alpha, a_flange = flange_motion(model, q, qd, qdd)
    mount = np.eye(4) if mount is None else mount
    R_f, p_f = pose[:3, :3], pose[:3, 3]
    R = R_f @ mount[:3, :3]
    origin = p_f + R_f @ mount[:3, 3]
    payload = model.payload
    r_com = R_f @ np.asarray(payload.com)  # flange origin -> CoM, base axes
    a_com = a_flange + _cross(alpha, r_com) + _cross(w, _cross(w, r_com))
    inertia = R_f @ inertia_matrix(payload.inertia) @ R_f.T
    force = payload.mass * (np.asarray(model.gravity) - a_com)
    torque = _cross(p_f + r_com - origin, force) - inertia @ alpha - _cross(w, inertia @ w)
    return np.concatenate([R.T @ force, R.T @ torque]), R


def contact_wrench(
    model: RobotModel, q, qd, qdd, reading, mount: np.ndarray | None = None, bias=NO_BIAS, frame: str = "sensor"
) -> np.ndarray:
    """The wrench the environment exerts on the tool, (force [N]; torque [N m] about the
    sensor's origin), in the axes of ``frame`` (see the module). ValueError for states or a
    reading that are not finite numbers of the right length, or another frame."""
    if frame not in FRAMES:
        raise ValueError(f"ft_contact_wrench.frame: must be one of {', '.join(FRAMES)}; got {frame!r}")
    reading, bias = np.asarray(state(reading, 6, "reading")), np.asarray(state(bias, 6, "bias"))
    w_tool, R = tool_wrench(model, q, qd, qdd, mount)
    contact = reading - bias - w_tool
    if frame == "base":
        contact = np.concatenate([R @ contact[:3], R @ contact[3:]])
    return contact


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u x v of 3-vectors (np.cross costs ten times more)."""
    (ux, uy, uz), (vx, vy, vz) = u.tolist(), v.tolist()
    return np.array([uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx])


def _rigid_inverse(T: np.ndarray) -> np.ndarray:
    inverse = np.eye(4)
    inverse[:3, :3] = T[:3, :3].T
    inverse[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return inverse
