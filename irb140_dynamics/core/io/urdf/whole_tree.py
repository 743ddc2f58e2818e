"""A URDF's whole kinematic tree below base_link as one RobotModel (``load_urdf`` with no
tip_link and several leaves: two arms on a torso, an arm with a head).

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

from irb140_dynamics.core.io.urdf.reader import (
    MOVING,
    LoadedUrdf,
    _checked_inertials,
    _joint,
    base_gravity,
    base_rotation,
    compose,
    lumped,
    mimics_of,
)
from irb140_dynamics.core.io.urdf.tree import UrdfError, UrdfTree, clipped, inertial_problem
from irb140_dynamics.core.model.joints import Placement
from irb140_dynamics.core.model.rigid_body import ModelError
from irb140_dynamics.core.model.robot_model import RobotModel


def moving_joints(tree: UrdfTree, base: str) -> tuple[list, list[int], list[Placement]]:
    """(the moving joints below ``base``, depth first in the file's order; each one's parent
    index, -1 for none; each one's origin in its parent's link frame, the fixed joints
    between them composed). UrdfError for a floating or planar joint."""
    moving, parents, origins = [], [], []
    # (joint, index of the moving joint whose link its parent link is fixed to, the
    # placement of its parent link in that link): a joint's subtree is pushed on top of its
    # next siblings, so the walk is depth first in the file's order (preorder)
    stack = [(joint, -1, Placement()) for joint in reversed(tree.child_joints[base])]
    while stack:
        joint, above, placement = stack.pop()
        if joint.kind in MOVING:
            moving.append(joint)
            parents.append(above)
            origins.append(compose(placement, joint.origin))
            above, placement = len(moving) - 1, Placement()
        elif joint.kind == "fixed":
            placement = compose(placement, joint.origin)
        else:
            hint = " (a floating base: name the link under it as base_link)" if joint.kind == "floating" else ""
            raise UrdfError(
                joint.label,
                f"a {joint.kind} joint below {clipped(repr(base), 60)}: only revolute, continuous, "
                f"prismatic and fixed joints are supported{hint}",
            )
        stack += [(child, above, placement) for child in reversed(tree.child_joints[joint.child])]
    return moving, parents, origins


def load_tree(tree: UrdfTree, base: str, max_joints: int) -> LoadedUrdf:
    """The whole tree below ``base`` as a LoadedUrdf (see the module)."""
    moving, parents, origins = moving_joints(tree, base)
    where = f"below {clipped(repr(base), 60)}"
    if not moving:
        raise UrdfError("tree", f"no revolute, continuous or prismatic joint {where}")
    if len(moving) > max_joints:
        raise UrdfError(
            "tree", f"{len(moving)} moving joints {where}, more than the limit of {max_joints} (max_joints)"
        )
    stops = {joint.name for joint in moving}
    held: list[str] = []
    carried: list[list[str]] = []
    bodies = [lumped(tree, joint.child, stops, held, carried) for joint in moving]
    warnings, physical = _checked_inertials(tree, carried)
    subtree_mass = [body.mass for body, _ in bodies]
    for i in reversed(range(len(moving))):
        if parents[i] >= 0:
            subtree_mass[parents[i]] += subtree_mass[i]
    for joint, mass in zip(moving, subtree_mass):
        if mass == 0.0:
            warnings.append(
                f'URDF joint "{clipped(joint.name, 100)}": moves no mass (M(q) is singular: forward '
                "dynamics needs a payload)"
            )
    joints = [
        _joint(joint, placement, body, ok) for joint, placement, (body, _), ok in zip(moving, origins, bodies, physical)
    ]
    try:
        model = RobotModel(
            tuple(joints), gravity=base_gravity(tree, base), parent=tuple(parents), mimics=mimics_of(moving)
        )
    except ModelError as error:
        raise UrdfError("tree", str(error)) from None
    in_model = {name for names in carried for name in names}
    notes = [
        f"{problem[1]} (not moved by the tree: ignored)"
        for name, body in tree.inertials.items()
        if name not in in_model and (problem := inertial_problem(name, body))
    ]
    rotation = tuple(tuple(float(x) for x in row) for row in base_rotation(tree, base))
    return LoadedUrdf(model, base, moving[-1].child, (), tuple(warnings), tuple(notes), rotation, tree.name)
