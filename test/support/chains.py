"""Long serial chains built in code: arms beyond the reach of the payload proofs (more than
9 joints get plain interval bounds, whose budget they exhaust) and slow to analyse (30
joints: the search alone takes many seconds)."""

import math

from irb140_dynamics.core import DH, Joint, RigidBody, RobotModel
from irb140_dynamics.core.urdf import export_urdf


def chain(n: int, torque_limit: float = 0.0) -> RobotModel:
    """n revolute joints, their axes turning by +-90 deg from one to the next, 2 kg links
    0.1 m apart, ranges +-2.5 rad; ``torque_limit`` on every joint (0: derived)."""
    joints = []
    for i in range(n):
        alpha = math.pi / 2 if i % 2 == 0 else -math.pi / 2
        link = RigidBody(2.0, (0.05, 0.0, 0.0), (0.01, 0.01, 0.01, 0.0, 0.0, 0.0))
        joints.append(Joint(f"joint_{i + 1}", DH(0.1, alpha, 0.05, 0.0), link, (-2.5, 2.5), torque_limit=torque_limit))
    return RobotModel(tuple(joints))


def chain_urdf(n: int) -> str:
    """The chain of n joints as URDF text."""
    return export_urdf(chain(n), name=f"chain_{n}")
