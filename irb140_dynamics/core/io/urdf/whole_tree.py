"""A URDF's whole kinematic tree below base_link: its moving joints, as ``load_urdf`` reads
them with no tip_link and several leaves (two arms on a torso, an arm with a head); and
``compose``, of placements.

- Every revolute, continuous and prismatic joint below base_link is a joint of the model,
  depth first in the file's order (a joint, then everything below it, then the next joint
  of the same link): ``model.joints``, their parents in ``model.parent``, the independent
  ones' names ``model.joint_names``.
- Fixed joints are merged as in a chain: a body fixed to a moving link is lumped into it,
  the fixed joints between a moving joint and the next one below it make up that one's
  origin; bodies fixed to base_link do not move and are left out. The model's flange is
  the last joint's link frame, the ``tip_link`` reported (where a payload would sit).
- Mimic joints follow their joint (see ``reader.mimics_of``).
- A floating or planar joint below base_link is refused, naming it. A URDF whose root is
  a floating base (a humanoid written with its free-flyer joint) is read from the link
  under that joint: name it as base_link, and what is above it (the floating joint) is
  left out, as everything above base_link is; gravity is the root's -z with it at zero.
"""

from __future__ import annotations

import numpy as np

from irb140_dynamics.core.io.urdf.held import motion_placement
from irb140_dynamics.core.io.urdf.tree import MOVING, UrdfError, UrdfTree, clipped, in_leader_order
from irb140_dynamics.core.model.joints import Placement, matrix_rpy
from irb140_dynamics.core.model.tree import Mimic


def moving_joints(tree: UrdfTree, base: str) -> tuple[list, list[int], list[Placement]]:
    """(the moving joints below ``base``, depth first in the file's order; each one's parent
    index, -1 for none; each one's origin in its parent's link frame, the fixed joints
    between them composed). UrdfError for a floating or planar joint."""

    def fixed(joint, placement: Placement) -> Placement:
        if joint.kind == "fixed":
            return compose(placement, joint.origin)
        hint = " (a floating base: name the link under it as base_link)" if joint.kind == "floating" else ""
        raise UrdfError(
            joint.label,
            f"a {joint.kind} joint below {clipped(repr(base), 60)}: only revolute, continuous, "
            f"prismatic and fixed joints are supported{hint}",
        )

    return _preorder(tree, [(joint, -1) for joint in tree.child_joints[base]], lambda j: j.kind in MOVING, fixed)


def chain_followers(tree: UrdfTree, chain: list, mimics: tuple | None) -> dict:
    """Every mimic joint off ``chain`` that follows a joint of it, or a joint that does (a mimic
    of a mimic): name -> its ``Mimic`` of the independent chain joint it comes to, the
    multipliers and offsets composed. ``mimics``: the chain's (``reader.mimics_of``)."""
    names = {joint.name for joint in chain}
    follows = {j.name: m for j, m in zip(chain, mimics or ()) if m is not None}
    pending = [j for j in tree.joints.values() if j.kind in MOVING and j.name not in names]
    for joint in in_leader_order(pending, names):
        mimic, above = joint.mimic, follows.get(joint.leader, Mimic(joint.leader))  # above: the chain joint it comes to
        follows[joint.name] = Mimic(
            above.joint, mimic.multiplier * above.multiplier, mimic.multiplier * above.offset + mimic.offset
        )
    return {name: mimic for name, mimic in follows.items() if name not in names}


def refuse_followers_above(tree: UrdfTree, base: str, follows: dict) -> None:
    """UrdfError for a mimic joint above base_link that follows a joint of the model: it would turn base_link."""
    for joint in tree.path_from_root(base):
        if joint.name in follows:
            raise UrdfError(
                joint.label,
                f"a mimic joint above base_link {clipped(repr(base), 60)} following {follows[joint.name].joint!r}, "
                "a joint of the chain: name a base_link above it",
            )


def mimic_branches(tree: UrdfTree, chain: list, follows: dict, held=None) -> tuple[list, list[int], list]:
    """The joints of ``follows`` (``chain_followers``) hanging below ``chain``'s links, as
    joints of the model: (them, depth first below each chain link in the file's order; each
    one's parent index among chain + them; each one's origin in its parent's link frame, the
    fixed and held joints between composed, held at ``held``'s positions, else zero)."""
    names, held = {joint.name for joint in chain}, held or {}

    def held_at(joint, placement: Placement) -> Placement:
        return compose(compose(placement, joint.origin), motion_placement(joint, held.get(joint.name, 0.0)))

    starts = [(j, k) for k in range(len(chain)) for j in tree.child_joints[chain[k].child] if j.name not in names]
    return _preorder(tree, starts, lambda j: j.name in follows, held_at, names, len(chain))


def _preorder(tree: UrdfTree, starts: list, counted, passed, left_out=frozenset(), first: int = 0) -> tuple:
    """(the joints ``counted`` below ``starts`` ((joint, the index of the model's joint above
    it)), depth first in the file's order; each one's parent index; each one's origin in its
    parent's link frame): another joint is passed through, ``passed(joint, placement)`` the
    placement past it; the joints named in ``left_out`` and what is below them are not
    walked; the joints found are numbered from ``first``."""
    found, parents, origins = [], [], []
    # a joint's subtree is pushed on top of its next siblings: depth first in the file's order
    stack = [(joint, above, Placement()) for joint, above in reversed(starts)]
    while stack:
        joint, above, placement = stack.pop()
        if counted(joint):
            found.append(joint)
            parents.append(above)
            origins.append(compose(placement, joint.origin))
            above, placement = first + len(found) - 1, Placement()
        else:
            placement = passed(joint, placement)
        stack += [(j, above, placement) for j in reversed(tree.child_joints[joint.child]) if j.name not in left_out]
    return found, parents, origins


def carried_links(tree: UrdfTree, moving: list, held=None) -> dict[str, tuple[str, Placement]]:
    """Every link a moving joint of the model carries, fixed to its link or behind held joints
    (at ``held``'s positions, else zero: ``held.held_positions``): link -> (that joint's name,
    the link's frame in the joint's link frame)."""
    names, held = {joint.name for joint in moving}, held or {}
    found = {}
    for joint in moving:
        stack = [(joint.child, Placement())]
        while stack:
            link, placement = stack.pop()
            found[link] = (joint.name, placement)
            stack += [
                (j.child, compose(compose(placement, j.origin), motion_placement(j, held.get(j.name, 0.0))))
                for j in tree.child_joints[link]
                if j.name not in names
            ]
    return found


def compose(a: Placement, b: Placement) -> Placement:
    """The placement a * b; exact when either is a pure translation or the identity."""
    if a.is_identity:
        return b
    if b.is_identity:
        return a
    xyz = tuple((np.array(a.xyz) + a.rotation() @ np.array(b.xyz)).tolist())
    if b.rpy == (0.0, 0.0, 0.0):
        return Placement(xyz, a.rpy)
    if a.rpy == (0.0, 0.0, 0.0):
        return Placement(xyz, b.rpy)
    return Placement(xyz, matrix_rpy(a.rotation() @ b.rotation()))
