"""The joints a URDF's model leaves out, held at positions given: the rest of a tree (a second
arm, a head, a gripper's fingers) while the model is one chain of it (a tip_link named), and
the joints above base_link. Each is where given, else at its default (below).

A held joint's position places what hangs from it: the bodies lumped into the chain link
they hang from (``reader.lumped``), the links a payload may hang on
(``whole_tree.carried_links``) and, above base_link, gravity's direction in base_link's
frame (``reader.base_rotation``). Held joints are at rest: the model's torques are those of
the whole tree at the same positions with the held joints still.

A joint not given is at zero, or where zero is outside its <limit lower upper> at the limit
nearest zero (a ``note`` says so: ``default_note``). A mimic joint is not given: it follows
its joint, ``multiplier * q + offset``, given or not (a mimic of a mimic so too); one
following a joint of the model is no held joint but the model's (``whole_tree.mimic_branches``).
Refused with ``HeldError`` (one line, naming the joint): a joint the URDF does not have (with
the nearest name), a fixed, floating or planar one, a joint of the model (its position is the
state's), a mimic joint, a value not finite or outside the joint's <limit lower upper>.
Units: rad (revolute, continuous), m (prismatic).
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Collection, Mapping

import numpy as np

from irb140_dynamics.core.io.urdf.tree import MOVING, UrdfError, UrdfJoint, UrdfTree, clipped, in_leader_order, number
from irb140_dynamics.core.model.joints import Placement, axis_rotation, matrix_rpy


class HeldError(UrdfError):
    """A held position refused; ``joint``: the joint whose given position it is (a mimic
    joint's refusal names the joint it follows)."""

    def __init__(self, joint: str, reason: str):
        super().__init__(f'held joint "{joint}"', reason)
        self.joint = joint


def held_positions(
    tree: UrdfTree, in_model: Collection[str], given: Mapping[str, float], at_limit: list | None = None
) -> dict[str, float]:
    """Every moving joint off the model at its held position (the module's): given (checked),
    else its default (``default_position``), a mimic joint following its joint. ``in_model``:
    the model's joints' names (mimic joints too); ``at_limit``: the names of the joints not
    given and held at a limit are appended to it."""
    for name in given:
        _check_given(tree, in_model, name)
    positions, given_by = {}, {}  # given_by: the joint given that a mimic joint follows (None: a default)
    for joint in tree.joints.values():
        if joint.kind not in MOVING or joint.name in in_model or joint.element.find("mimic") is not None:
            continue
        if joint.name in given:
            positions[joint.name] = _within_limits(joint, float(given[joint.name]), "", joint.name)
            given_by[joint.name] = joint.name
        else:
            positions[joint.name], limited = default_position(joint)
            given_by[joint.name] = None
            if limited and at_limit is not None:
                at_limit.append(joint.name)
    followers = [j for j in tree.joints.values() if j.kind in MOVING and j.name not in in_model]
    for joint in in_leader_order(followers, list(positions)):
        mimic = joint.mimic
        position = mimic.multiplier * positions[joint.leader] + mimic.offset
        given_by[joint.name] = source = given_by[joint.leader]
        if source is not None:  # a default places a mimic joint where the URDF's tree at that position does
            position = _within_limits(joint, position, f" for mimic joint {joint.name!r}", source)
        positions[joint.name] = position
    return positions


def _check_given(tree: UrdfTree, in_model: Collection[str], name: str) -> None:
    """HeldError unless ``name`` is a moving joint off the model and no mimic joint."""
    joint = tree.joints.get(name)
    if joint is None:
        known = [n for n, j in tree.joints.items() if j.kind in MOVING]
        near = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
        hint = f"; did you mean {near[0]}?" if near else ""
        raise HeldError(name, f"the URDF has no joint {clipped(repr(name), 80)}{hint}")
    if joint.kind not in MOVING:
        raise HeldError(name, f"a {joint.kind} joint: only revolute, continuous and prismatic joints are held")
    leader = joint.leader
    if name in in_model:
        of = f"a mimic joint of the model following {clipped(repr(leader), 80)}" if leader is not None else ""
        raise HeldError(name, f"{of or 'a joint of the model'}, not held: its position is the state's")
    if joint.element.find("mimic") is not None:
        raise HeldError(
            name,
            f"a mimic joint: it follows {clipped(repr(leader), 80)} (multiplier * q + offset); "
            "give that joint's position",
        )


def default_position(joint: UrdfJoint) -> tuple[float, bool]:
    """(where a joint not given is held, whether that is a limit): zero, or the limit nearest
    zero when its <limit lower upper> excludes zero (a continuous joint, one without <limit>
    or with one unreadable: zero)."""
    limit = joint.element.find("limit")
    if joint.kind == "continuous" or limit is None:
        return 0.0, False
    try:
        lower, upper = number(limit, "lower", joint.label, 0.0), number(limit, "upper", joint.label, 0.0)
    except UrdfError:  # the model's joints' limits are checked where they are read; a held one's only if given
        return 0.0, False
    if lower <= 0.0 <= upper or lower > upper:
        return 0.0, False
    return (lower if lower > 0.0 else upper), True


def default_note(joint: UrdfJoint, value: float) -> str:
    """The note of a joint held at a limit by default (``default_position``)."""
    unit = "m" if joint.kind == "prismatic" else "rad"
    return (
        f"{joint.label}: not given, held at {value:g} {unit}, its limit nearest zero (zero is outside its range); "
        "give its position to hold it elsewhere"
    )


def _within_limits(joint: UrdfJoint, value: float, why: str, given: str) -> float:
    """``value``, or HeldError naming the joint ``given``: not finite, or outside the joint's
    <limit lower upper> (a continuous joint, or one without <limit>, has none)."""
    unit = "m" if joint.kind == "prismatic" else "rad"
    if not math.isfinite(value):
        raise HeldError(given, f"the position must be finite, got {value}{why}")
    limit = joint.element.find("limit")
    if joint.kind == "continuous" or limit is None:
        return value
    where = f"{joint.label} <limit>"
    lower, upper = number(limit, "lower", where, 0.0), number(limit, "upper", where, 0.0)
    if not lower <= value <= upper:
        raise HeldError(given, f"{value:g} {unit}{why} is outside its limits [{lower:g}, {upper:g}] {unit}")
    return value


def motion(joint: UrdfJoint, q: float) -> np.ndarray:
    """The 4x4 transform a moving joint at ``q`` puts between its origin and its child link."""
    T = np.eye(4)
    if joint.kind == "prismatic":
        T[:3, 3] = np.asarray(joint.axis, dtype=float) * q
    else:
        T[:3, :3] = axis_rotation(joint.axis, q)
    return T


def motion_placement(joint: UrdfJoint, q: float) -> Placement:
    """``motion`` as a Placement; the identity (exactly) at q = 0."""
    if q == 0.0:
        return Placement()
    T = motion(joint, q)
    return Placement(tuple(T[:3, 3].tolist()), matrix_rpy(T[:3, :3]))
