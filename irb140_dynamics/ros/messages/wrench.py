"""geometry_msgs/WrenchStamped at the flange <-> (force, torque) arrays, and the frames they name.

A flange wrench is (force [N]; torque [N m] about the flange origin), in the axes of the
tip link (the flange) or of the base link, named by ``header.frame_id`` (REP 103 units).
The links are the URDF's: for a model of parameters, the names ``export_urdf`` writes
(``base_link``, ``flange``); for a model of a URDF, its chain's base and tip links.
"""

from __future__ import annotations

import math

import numpy as np
from geometry_msgs.msg import WrenchStamped

from irb140_dynamics.core.io.urdf.writer import BASE, FLANGE
from irb140_dynamics.core.model.joint_order import BadMessage

MAX_FORCE = 1e5  # N: beyond what any arm's flange takes; a larger wrench is refused as absurd
MAX_TORQUE = 1e4  # N m


def chain_links(parameters) -> tuple[str, str]:
    """(base link, tip link) of a node's model: its URDF's chain when it came from one
    (``chain_links`` of ros.parameters.arm), else export_urdf's names."""
    return getattr(parameters, "chain_links", None) or (BASE, FLANGE)


def fill_wrench(msg: WrenchStamped, stamp, frame_id: str, force, torque) -> WrenchStamped:
    """``msg`` with the stamp (a builtin_interfaces/Time), frame and six finite numbers."""
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp.sec, stamp.nanosec
    msg.header.frame_id = frame_id
    f, m = msg.wrench.force, msg.wrench.torque
    f.x, f.y, f.z = (float(x) for x in force)
    m.x, m.y, m.z = (float(x) for x in torque)
    return msg


def read_wrench(msg: WrenchStamped, links: tuple[str, str]) -> tuple[np.ndarray, str]:
    """(force; torque) as 6 numbers and the axes they are in, ``tip`` or ``base``, or
    BadMessage: a frame other than the two links, a value not finite or absurd."""
    base, tip = links
    frame = {tip: "tip", base: "base"}.get(msg.header.frame_id)
    if frame is None:
        raise BadMessage(
            "unknown_frame",
            f"frame_id {msg.header.frame_id[:80]!r} is neither the tip link {tip!r} nor the base {base!r}",
        )
    f, m = msg.wrench.force, msg.wrench.torque
    values = np.array([f.x, f.y, f.z, m.x, m.y, m.z], dtype=float)
    if not np.isfinite(values).all():
        raise BadMessage("not_finite", f"wrench not finite: {values.tolist()}")
    force, torque = math.hypot(*values[:3]), math.hypot(*values[3:])
    if force > MAX_FORCE or torque > MAX_TORQUE:
        raise BadMessage(
            "absurd_wrench",
            f"|force| {force:.3g} N, |torque| {torque:.3g} N m: at most {MAX_FORCE:g} N and {MAX_TORQUE:g} N m",
        )
    return values, frame
