"""Link inertials from simple shapes of one density: the report's appendix A.1.

The IRB-140's moving links are modelled as a cylinder (link 1), two square-section boxes
(links 2 and 4) and a cylinder (link 6); links 3 and 5 have no length and no mass. The
density is solved so that the moving links weigh 78 kg (98 kg arm less a 20 kg base).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from irb140_dynamics.core.model.rigid_body import RigidBody
from irb140_dynamics.core.model.robot_model import DH, Joint, RobotModel

_AXES = "xyz"


def cylinder_volume(radius: float, height: float) -> float:
    return math.pi * radius**2 * height


def box_volume(size: Sequence[float]) -> float:
    return size[0] * size[1] * size[2]


def cylinder_inertia(mass: float, radius: float, height: float, axis: str):
    """Inertia about the centre of a solid cylinder whose axis is ``axis`` ('x', 'y' or 'z')."""
    across = mass / 12 * (3 * radius**2 + height**2)
    along = mass / 2 * radius**2
    moments = [along if a == axis else across for a in _AXES]
    return (*moments, 0.0, 0.0, 0.0)


def box_inertia(mass: float, size: Sequence[float]):
    """Inertia about the centre of a solid box with edges ``size`` along x, y, z."""
    x, y, z = size
    return (mass / 12 * (y**2 + z**2), mass / 12 * (x**2 + z**2), mass / 12 * (x**2 + y**2), 0.0, 0.0, 0.0)


def solve_density(target_mass: float, volumes: Sequence[float]) -> float:
    """The one density at which bodies of these volumes weigh ``target_mass`` together."""
    return target_mass / sum(volumes)


# The report's chosen sizes (Table 2) and density (3200 kg/m^3, the rounded pick).
IRB140_MOVING_MASS = 78.0  # kg: 98 kg arm less a 20 kg fixed base
IRB140_DENSITY = 3200.0  # kg/m^3
IRB140_LINK1 = dict(radius=0.098, height=0.2)  # cylinder along y1
IRB140_LINK2 = (0.36, 0.15, 0.15)  # box, length along x2
IRB140_LINK4 = (0.146, 0.38, 0.146)  # box, length along y4
IRB140_LINK6 = dict(radius=0.108, height=0.065)  # cylinder along z6

# Joint ranges: the ABB IRB 140 data sheet's axis ranges in this model's convention
# (q2 = -axis 2, q3 = -axis 3; the zero poses coincide), in degrees.
IRB140_RANGES_DEG = ((-180, 180), (-110, 90), (-50, 230), (-200, 200), (-115, 115), (-400, 400))
IRB140_SPEEDS_DEG = (200, 200, 260, 360, 360, 450)  # deg/s, the data sheet's axis speeds
IRB140_ACCELERATIONS = (14.0, 14.0, 18.0, 25.0, 25.0, 31.0)  # rad/s^2: assumed (not published)


@dataclass(frozen=True)
class Cylinder:
    """A solid cylinder about its centre, its axis along ``axis`` of its link's frame."""

    radius: float
    height: float
    axis: str = "z"


@dataclass(frozen=True)
class Box:
    """A solid box about its centre, edges ``size`` along its link frame's x, y, z."""

    size: tuple[float, float, float]


# The shapes of the links, by the joint that moves them (for drawing: see urdf.export_urdf).
IRB140_SHAPES = {
    "joint_1": Cylinder(axis="y", **IRB140_LINK1),
    "joint_2": Box(IRB140_LINK2),
    "joint_4": Box(IRB140_LINK4),
    "joint_6": Cylinder(axis="z", **IRB140_LINK6),
}


def irb140_volumes(link1=IRB140_LINK1, link2=IRB140_LINK2, link4=IRB140_LINK4, link6=IRB140_LINK6) -> list[float]:
    return [cylinder_volume(**link1), box_volume(link2), box_volume(link4), cylinder_volume(**link6)]


NO_PAYLOAD = RigidBody()


def irb140(density: float = IRB140_DENSITY, payload: RigidBody = NO_PAYLOAD) -> RobotModel:
    """The report's IRB-140 model (its DH table and shapes) at the given density."""
    m1 = density * cylinder_volume(**IRB140_LINK1)
    m2 = density * box_volume(IRB140_LINK2)
    m4 = density * box_volume(IRB140_LINK4)
    m6 = density * cylinder_volume(**IRB140_LINK6)
    links = [
        RigidBody(m1, (0.0, -0.1, 0.0), cylinder_inertia(m1, axis="y", **IRB140_LINK1)),
        RigidBody(m2, (-0.18, 0.0, 0.0), box_inertia(m2, IRB140_LINK2)),
        RigidBody(),
        RigidBody(m4, (0.0, 0.19, 0.0), box_inertia(m4, IRB140_LINK4)),
        RigidBody(),
        RigidBody(m6, (0.0, 0.0, -0.0325), cylinder_inertia(m6, axis="z", **IRB140_LINK6)),
    ]
    half_pi = math.pi / 2
    dh = [
        DH(0.0, half_pi, 0.2, 0.0),
        DH(0.36, 0.0, 0.0, half_pi),
        DH(0.0, half_pi, 0.0, 0.0),
        DH(0.0, -half_pi, 0.38, 0.0),
        DH(0.0, half_pi, 0.0, 0.0),
        DH(0.0, 0.0, 0.065, 0.0),
    ]
    joints = tuple(
        Joint(
            f"joint_{i + 1}",
            row,
            link,
            tuple(math.radians(x) for x in limits),
            velocity_limit=math.radians(speed),
            acceleration_limit=acceleration,
        )
        for i, (row, link, limits, speed, acceleration) in enumerate(
            zip(dh, links, IRB140_RANGES_DEG, IRB140_SPEEDS_DEG, IRB140_ACCELERATIONS)
        )
    )
    return RobotModel(joints, (0.0, 0.0, -9.81), payload)
