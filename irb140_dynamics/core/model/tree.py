"""A model's tree and mimic joints: the checks of ``RobotModel.parent`` and ``mimics``, and
their parameter form (see ``robot_model``).

``parent[i]`` is the index of joint i's parent joint in ``RobotModel.joints`` (-1: the base),
parents before children, as spatial_v2's ``model.parent``. A ``Mimic`` joint follows an
independent joint: q = multiplier * q_joint + offset; its torque, friction and armature
included, is carried by that joint (tau = G^T tau_all by virtual work, see
``RobotModel.mimic_matrix``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from irb140_dynamics.core.model.joints import param_prefix
from irb140_dynamics.core.model.rigid_body import ModelError, capped, finite_number

MAX_MULTIPLIER = 1e3  # sanity cap of a mimic joint's |multiplier|


@dataclass(frozen=True)
class Mimic:
    """A joint that follows another (URDF <mimic>): q = multiplier * q_joint + offset, its
    velocity and acceleration ``multiplier`` times the followed joint's. ``joint``: the
    followed joint's name, an independent joint of the model."""

    joint: str
    multiplier: float = 1.0
    offset: float = 0.0  # rad (m for a prismatic joint)


def checked_parents(parent, count: int) -> tuple[int, ...]:
    """The parent indices as a tuple (None, or a chain's of any length: a chain), or
    ModelError: one per joint, each -1 (the base) or an earlier joint's index."""
    if parent is None or (isinstance(parent, tuple) and parent == tuple(range(-1, len(parent) - 1))):
        return tuple(range(-1, count - 1))  # a chain's, also when joints are added (dataclasses.replace)
    if not isinstance(parent, (list, tuple)) or len(parent) != count:
        raise ModelError("joint_parents", f"expected one parent index per joint ({count}), got {parent!r}"[:250])
    out = []
    for i, p in enumerate(parent):
        if isinstance(p, bool) or not isinstance(p, int) or not -1 <= p < i:
            raise ModelError("joint_parents", f"joint {i}'s parent must be -1 or an earlier joint's index, got {p!r}")
        out.append(int(p))
    return tuple(out)


def checked_mimics(mimics, joints) -> tuple | None:
    """The mimic joints as a tuple (None: none), or ModelError: one entry per joint, each
    None or a Mimic following an independent joint of the model (not a mimic joint, not
    itself), a finite multiplier and offset."""
    if mimics is None or all(m is None for m in mimics):
        return None
    if len(mimics) != len(joints):
        raise ModelError("mimic_joints", f"expected one entry per joint ({len(joints)}), got {len(mimics)}")
    followers = {j.name for j, m in zip(joints, mimics) if m is not None}
    names = {j.name for j in joints}
    out = []
    for joint, mimic in zip(joints, mimics):
        if mimic is None:
            out.append(None)
            continue
        key = f"{param_prefix(joint.name)}.mimic"
        if not isinstance(mimic, Mimic):
            raise ModelError(key, f"expected a Mimic, got {mimic!r}"[:200])
        leader = mimic.joint
        if leader == joint.name:
            raise ModelError(key, f"joint {joint.name!r} cannot follow itself")
        if leader not in names:
            raise ModelError(key, f"follows {str(leader)[:80]!r}, not a joint of the model")
        if leader in followers:
            raise ModelError(key, f"follows {leader!r}, itself a mimic joint (a mimic of a mimic is not supported)")
        multiplier = finite_number(f"{key}.multiplier", mimic.multiplier)
        offset = finite_number(f"{key}.offset", mimic.offset)
        capped(f"{key}.multiplier", "|multiplier|", abs(multiplier), MAX_MULTIPLIER, "")
        if joint.friction.coulomb and abs(multiplier) != 1.0:
            raise ModelError(
                f"{param_prefix(joint.name)}.friction.coulomb",
                f"a mimic joint's Coulomb friction is supported with multiplier +-1 only, got {multiplier}",
            )
        out.append(Mimic(leader, multiplier, offset))
    return tuple(out)


def tree_params(model) -> dict[str, Any]:
    """The parameters of a model's tree and mimic joints (see ``robot_model``)."""
    names = [j.name for j in model.joints]
    params: dict[str, Any] = {
        "tree.joints": names,
        "tree.parents": [names[p] if p >= 0 else "" for p in model.parent],
    }
    for joint, mimic in zip(model.joints, model.mimics or ()):
        if mimic is not None:
            key = param_prefix(joint.name)
            params[f"{key}.mimic.joint"] = mimic.joint
            params[f"{key}.mimic.multiplier"] = mimic.multiplier
            params[f"{key}.mimic.offset"] = mimic.offset
    return params


def tree_from_params(names: list[str], params: Mapping[str, Any], get) -> tuple[tuple, tuple]:
    """(parent, mimics) of ``tree.joints`` from tree.parents and <joint>.mimic.*."""
    parents = get("tree.parents")
    if not isinstance(parents, (list, tuple)) or len(parents) != len(names):
        raise ModelError("tree.parents", f'expected one name (or "") per joint of tree.joints ({len(names)})')
    index = {name: i for i, name in enumerate(names)}
    parent = []
    for i, name in enumerate(parents):
        if name != "" and index.get(name, i) >= i:
            raise ModelError("tree.parents", f"{str(name)[:80]!r} is not a joint before {names[i]!r} in tree.joints")
        parent.append(-1 if name == "" else index[name])
    mimics = []
    for name in names:
        key = f"{param_prefix(name)}.mimic"
        leader = params.get(f"{key}.joint")
        if leader is None or leader == "":
            mimics.append(None)
        elif not isinstance(leader, str):
            raise ModelError(f"{key}.joint", f"expected a joint's name, got {leader!r}"[:200])
        else:
            mimics.append(Mimic(leader, get(f"{key}.multiplier", 1.0), get(f"{key}.offset", 0.0)))
    return tuple(parent), tuple(mimics)
