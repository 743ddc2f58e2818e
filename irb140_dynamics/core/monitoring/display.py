"""How the arm's loads are drawn (RViz markers, previews): the numbers behind the pictures.

- A joint's load is |tau_j| / limit_j, limit_j the torque limit the payload check uses
  (``payload.limits.derive_torque_limits``: the given torque_limit, else the rated
  payload's worst static torque). Its colour runs green (0) to yellow (YELLOW_AT = 0.7)
  to red (1 and above), linearly in between; a joint without a limit is grey.
- The payload is a sphere of PAYLOAD_DENSITY (aluminium, 2700 kg/m^3) of its mass: 6 kg
  gives 0.162 m across; never less than MIN_PAYLOAD_DIAMETER, so that a light payload shows.
- A force is an arrow of ARROW_PER_NEWTON (0.01 m/N: 20 N draws 0.2 m), at most
  MAX_ARROW long (the length saturates; the label keeps the number).
- A joint of the state (every independent joint of a tree; a mimic joint is shown by the joint
  it follows) is a sphere of JOINT_DIAMETER at its origin; one at the place of earlier joints
  (within SAME_PLACE, e.g. a wrist's) nests inside them, NESTED times as large each.

Units: N m, kg, m, N. Colours are (red, green, blue) in 0..1.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from irb140_dynamics.core.kinematics import joint_origins_and_flange
from irb140_dynamics.core.monitoring.wrench import wrench_of

YELLOW_AT = 0.7  # load where the colour is yellow
GREEN, YELLOW, RED, GREY = (0.0, 1.0, 0.0), (1.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.5, 0.5, 0.5)
PAYLOAD_DENSITY = 2700.0  # kg/m^3
MIN_PAYLOAD_DIAMETER = 0.02  # m
ARROW_PER_NEWTON = 0.01  # m/N
MAX_ARROW = 2.0  # m
JOINT_DIAMETER = 0.06  # m
NESTED = 0.7
SAME_PLACE = 0.01  # m


def joint_loads(tau, limits) -> list[float | None]:
    """|tau_j| / limit_j per joint; None where the limit is none (inf or 0) or tau not finite."""
    return [
        abs(t) / limit if 0.0 < limit < math.inf and math.isfinite(t) else None
        for t, limit in zip(np.asarray(tau, dtype=float).tolist(), np.asarray(limits, dtype=float).tolist())
    ]


def load_colour(load: float | None) -> tuple[float, float, float]:
    """The colour of a load (see the module): green, yellow at YELLOW_AT, red from 1; grey for None."""
    if load is None or not math.isfinite(load):
        return GREY
    if load <= YELLOW_AT:
        return _mix(GREEN, YELLOW, max(load, 0.0) / YELLOW_AT)
    return _mix(YELLOW, RED, min((load - YELLOW_AT) / (1.0 - YELLOW_AT), 1.0))


def load_label(name: str, tau: float, load: float | None) -> str:
    """E.g. ``joint_3 81 % (85.2 N m)``; without a limit ``joint_1 (85.2 N m, no limit)``."""
    if load is None:
        return f"{name} ({amount(tau)} N m, no limit)"
    return f"{name} {percent(100.0 * load)} % ({amount(tau)} N m)"


def force_label(force) -> str:
    """The text of a force's arrow: its magnitude, e.g. ``50.0 N`` (finite whatever the
    components: ``1.2e+300 N``)."""
    return f"{amount(magnitude(force))} N"


def magnitude(vector) -> float:
    """|vector| without overflow on its way (math.hypot scales); the largest float where
    the length itself is beyond it."""
    length = math.hypot(*np.asarray(vector, dtype=float).tolist())
    return length if math.isfinite(length) else LARGEST


LARGEST = float(np.finfo(float).max)
PLAIN_BELOW = 1e6  # a number's magnitude from which a label writes it with an exponent


def amount(x: float) -> str:
    """A number for a label, one decimal (``85.2``); from PLAIN_BELOW with an exponent
    (``1.23e+300``, never 300 digits); ``nan`` or ``inf`` only for those."""
    return f"{x:.1f}" if abs(x) < PLAIN_BELOW else f"{x:.3g}"


def percent(x: float) -> str:
    """A load in percent for a label: ``81``, or with an exponent from PLAIN_BELOW."""
    return f"{x:.0f}" if abs(x) < PLAIN_BELOW else f"{x:.3g}"


def payload_diameter(mass: float) -> float:
    """The payload sphere's diameter [m]: a ball of PAYLOAD_DENSITY of ``mass`` [kg]."""
    mass = mass if math.isfinite(mass) and mass > 0.0 else 0.0
    return max(2.0 * (3.0 * mass / (4.0 * math.pi * PAYLOAD_DENSITY)) ** (1.0 / 3.0), MIN_PAYLOAD_DIAMETER)


def arrow_end(start, force) -> np.ndarray:
    """Where a force's arrow from ``start`` ends [m]: ARROW_PER_NEWTON per newton along it,
    at most MAX_ARROW."""
    force = np.asarray(force, dtype=float)
    start = np.asarray(start, dtype=float)
    if ARROW_PER_NEWTON * magnitude(force) <= MAX_ARROW:
        return start + ARROW_PER_NEWTON * force
    largest = float(np.max(np.abs(force)))  # huge forces: the direction without overflow
    direction = force / largest
    return start + MAX_ARROW * direction / magnitude(direction)


def _mix(a, b, share: float) -> tuple[float, float, float]:
    return tuple(x + share * (y - x) for x, y in zip(a, b))


class ArmPicture(NamedTuple):
    """Where the arm's markers go at one state, in the base frame [m], all finite."""

    origins: list  # (x, y, z) of each joint's origin
    earlier: list[int]  # per joint, how many earlier joints share its place
    diameters: list[float]  # of the joints' spheres
    payload: list  # (x, y, z) of the payload's centre of mass
    flange: list  # (x, y, z) of the flange origin
    force: np.ndarray | None  # N, base axes: the external force on the flange (None: not measured, or a tree)
    arrow_end: list | None  # (x, y, z) where its arrow ends
    loads: list  # |tau_j| / limit_j (see joint_loads)


def arm_picture(model, q, tau, limits=None, external=None) -> ArmPicture:
    """The picture of the state q with joint torques ``tau`` [N m] against ``limits`` (None:
    none known) and, if measured, the ``external`` joint torques; ValueError if a number
    is not finite. One pass of forward kinematics gives the places and the wrench."""
    origins, pose, J = joint_origins_and_flange(model, q)
    origins = origins[list(model.independent)]  # one sphere per joint of the state (a mimic joint's is its joint's)
    flange = pose[:3, 3]
    near = np.linalg.norm(origins[:, None, :] - origins[None, :, :], axis=2) < SAME_PLACE
    earlier = np.tril(near, -1).sum(axis=1).tolist()
    payload = pose[:3, :3] @ np.asarray(model.payload.com, dtype=float) + flange
    force = end = None
    numbers = [origins, payload, flange]
    if external is not None and model.is_chain:  # a tree's external torques are no one flange's force
        force = wrench_of(pose, J, external, "base").force
        end = arrow_end(flange, force)
        numbers.append(end)
    if not all(np.isfinite(x).all() for x in numbers):
        raise ValueError("markers not finite")
    loads = joint_loads(tau, np.full(model.n, np.inf) if limits is None else limits)
    diameters = [JOINT_DIAMETER * NESTED**k for k in earlier]
    end = None if end is None else end.tolist()
    return ArmPicture(origins.tolist(), earlier, diameters, payload.tolist(), flange.tolist(), force, end, loads)
