"""The limits a trajectory is held to, per joint: torque [N m], velocity [rad/s] and
acceleration [rad/s^2]; inf where there is none.

Torque: the params file's torque_limit where > 0, else the payload check's derived limit
(``derive_torque_limits``: the worst static torque of the rated payload over the joint
ranges, the permissible torque of the report's section 10); ``torque_source`` says which.
Velocity and acceleration: the params file's, 0 meaning none.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.payload import derive_torque_limits


@dataclass(frozen=True, eq=False)
class Limits:
    torque: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    torque_source: tuple[str, ...]  # per joint: "given", "derived" or "none"


def trajectory_limits(model: RobotModel) -> Limits:
    """The model's limits; torque limits of 0 derived as the payload check derives them."""
    given = np.array(model.torque_limits, dtype=float)
    if (given > 0).all():
        torque, source = given, ("given",) * model.n
    elif not model.is_chain:  # derived only for the joints up to the payload's link
        missing = ", ".join(name for name, limit in zip(model.joint_names, given) if limit <= 0)
        raise ValueError(f"{missing}: no torque_limit, and on a tree none is derived; give one (NAME.torque_limit)")
    else:
        derived = derive_torque_limits(model)
        torque, source = np.array(derived.values, dtype=float), derived.source
    return Limits(
        torque,
        _or_inf([j.velocity_limit for j in model.independent_joints]),
        _or_inf([j.acceleration_limit for j in model.independent_joints]),
        tuple(source),
    )


def _or_inf(values) -> np.ndarray:
    values = np.array(values, dtype=float)
    return np.where(values > 0, values, np.inf)


def torque_limit_notes(model: RobotModel, limits: Limits) -> tuple[str, ...]:
    """Lines saying which joints' torque limits were derived (or are none), for a report."""
    notes = []
    for source, text in (
        ("derived", "derived as the payload check does: the rated payload's worst static torque (torque_limit 0)"),
        ("none", "none: the rated payload cannot load them (torque_limit 0)"),
    ):
        names = [n for n, s in zip(model.joint_names, limits.torque_source) if s == source]
        if names:
            notes.append(f"torque limits of {', '.join(names)}: {text}")
    return tuple(notes)
