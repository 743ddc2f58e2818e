"""A URDF's chain from base_link to tip_link as a RobotModel.

- The chain's revolute, continuous and prismatic joints become the model's joints, in
  URDF form (origin, axis; link frames are the URDF's child links' frames), named as in
  the URDF (any name: the parameter form maps it, see ``model``).
- Fixed joints are merged: a body fixed to a moving link is lumped into it (inertial
  moved and turned into the link's frame), and the fixed joints between two moving
  joints make up the next one's origin. Fixed joints after the last moving joint up to
  tip_link give the model's ``flange`` (the tip_link frame, where the payload sits).
- Joints hanging off the chain (a gripper's fingers, another arm) are held where given
  (``load_urdf``'s ``held``), else at zero or the limit nearest it (module ``held``): their
  bodies are lumped into the chain link they hang from, their names returned. So are the
  joints above base_link. A mimic joint off the chain following a joint of it (a gripper's
  other finger) is the model's, hanging off the chain with what is below it
  (``whole_tree.mimic_branches``; ``flange_joint``: the chain's last joint).
- Bodies that do not move (base_link, what is fixed to it, what is above it) are left out;
  their inertials are not checked (an invalid one is a ``note``).
- Gravity is the root link's -z (9.81 m/s^2), expressed in base_link's frame with the
  joints between them held (where given, else at zero or the limit nearest it).
- <limit lower upper> are the position limits (continuous joints: CONTINUOUS_LIMITS),
  ``effort`` the torque (prismatic: force) limit, ``velocity`` the velocity limit (0 or
  absent: none); <dynamics damping friction> are viscous and Coulomb friction.
- The inertials the chain carries are checked: unreadable, not finite, a negative mass:
  refused; finite but not physically possible (triangle inequality, slightly negative
  moments, as vendor files have them): taken as given, with a ``warning`` naming the link.
- A joint that moves no mass (nothing after it has an inertial) is a ``warning``: M(q) is
  then singular, forward dynamics needs a payload.
- Mimic joints (<mimic joint multiplier offset>) follow their joint (``model.Mimic``): the
  model's ``joint_names`` are the others. One in the chain following a joint that is not in
  it is refused, as a mimic of a mimic there, and one above base_link following the chain.
- With no tip_link and several leaves below base_link, the whole tree (``whole_tree``).
- Refused, with UrdfError naming the element: floating and planar joints in the chain
  (or the tree); a revolute or prismatic joint without <limit>; a chain of more than
  ``max_joints`` moving joints; besides everything ``tree`` refuses (size, binary input,
  loops).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import partial, reduce

import numpy as np

from irb140_dynamics.core.io.text_files import InputFileError, read_text_file
from irb140_dynamics.core.io.urdf.held import default_note, held_positions, motion
from irb140_dynamics.core.io.urdf.tree import (
    MOVING,
    UrdfError,
    UrdfJoint,
    UrdfTree,
    checked_text,
    clipped,
    inertial_problem,
    number,
    parse_tree,
)
from irb140_dynamics.core.io.urdf.whole_tree import (
    carried_links,
    chain_followers,
    compose,
    mimic_branches,
    moving_joints,
    refuse_followers_above,
)
from irb140_dynamics.core.model.joints import MAX_TORQUE_LIMIT, Friction, Joint, Placement
from irb140_dynamics.core.model.rigid_body import ModelError, RigidBody, combine, placed
from irb140_dynamics.core.model.robot_model import RobotModel

CONTINUOUS_LIMITS = (-4 * math.pi, 4 * math.pi)  # rad: two turns either way, every angle within
MAX_JOINTS = 256  # moving joints of a chain or tree at most: TIAGo++ whole has 101; the kernels' trace
# grows with n (a 101-joint tree: M traced in 0.2 s) and M's with a chain's depth squared (a
# 256-joint chain: about 18 s), so a larger model would stall the first call
GRAVITY = 9.81  # m/s^2, along the root link's -z


@dataclass(frozen=True)
class LoadedUrdf:
    """The model of a URDF's chain and how it was read."""

    model: RobotModel
    base_link: str
    tip_link: str
    held_joints: tuple[str, ...]  # moving joints off the chain, held (module held), bodies lumped
    warnings: tuple[str, ...] = ()  # the chain's inertials taken as given though not physical
    notes: tuple[str, ...] = ()  # invalid inertials off the chain, ignored
    base_rotation: tuple = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))  # base_link's axes in the root's
    robot_name: str = ""  # <robot name="...">: the hardware_id of the nodes' /diagnostics
    carried: dict = field(default_factory=dict, compare=False, hash=False, repr=False)  # see with_flange_at
    held_positions: tuple[tuple[str, float], ...] = ()  # the held joints not at zero: given, or following one

    def held_summary(self) -> str:
        """'held at zero: a, b', or 'held: r1=0.4, r2=-0.7; at zero: a' (rad, m), for messages; '' for none."""
        at = dict(self.held_positions)
        zero = ", ".join(name for name in self.held_joints if name not in at)
        if not at:
            return f"held at zero: {zero}" if zero else ""
        given = ", ".join(f"{name}={value:g}" for name, value in at.items())
        return f"held: {given}" + (f"; at zero: {zero}" if zero else "")

    def with_flange_at(self, link: str) -> RobotModel:
        """The model with its flange (where the payload sits) at URDF link ``link``: on the
        link of the joint that carries it (``model.flange_joint``), placed as the URDF does
        (the joints off the chain held); UrdfError unless the model moves that link."""
        if link not in self.carried:
            raise UrdfError("link", f"{clipped(repr(link), 80)} is not moved by the model's joints")
        joint, placement = self.carried[link]
        return replace(self.model, flange_joint=joint, flange=placement)

    def in_base(self, vector) -> tuple[float, float, float]:
        """A vector given in the root link's frame (gravity) in base_link's frame."""
        return tuple(float(x) + 0.0 for x in np.asarray(self.base_rotation).T @ np.asarray(vector, dtype=float))


def load_urdf(
    text: str,
    base_link: str | None = None,
    tip_link: str | None = None,
    max_chars: int | None = None,
    max_joints: int = MAX_JOINTS,
    held: dict[str, float] | None = None,
) -> LoadedUrdf:
    """The chain from ``base_link`` (default: the root link) to ``tip_link`` as a RobotModel
    (gravity: the root's -z; payload: none). With no ``tip_link``, every moving joint below
    base_link: the chain to the only leaf, or the whole tree (see ``whole_tree``) when there
    are several. Mimic joints follow their joint (``model.Mimic``). ``max_chars``: the text's
    size limit (default: MAX_URDF_CHARS, or IRB140_MAX_FILE_BYTES). ``held``: positions of
    joints the model leaves out (rad, m; the rest at zero), HeldError naming a bad one (see
    ``held``)."""
    tree = parse_tree(text, max_chars)
    if not tip_link:
        tree._known("base_link", base_link or tree.root)
        if len(tree.leaves(base_link or tree.root)) > 1:
            return _load_tree(tree, base_link or tree.root, max_joints, held or {})
    base, tip, path = tree.chain(base_link, tip_link)
    span = f"from {clipped(repr(base), 60)} to {clipped(repr(tip), 60)}"
    for joint in path:
        if joint.kind not in ("fixed", *MOVING):
            raise UrdfError(
                joint.label,
                f"a {joint.kind} joint in the chain {span}: only revolute, continuous, "
                "prismatic and fixed joints are supported there",
            )
    moving = [joint for joint in path if joint.kind in MOVING]
    if not moving:
        raise UrdfError("chain", f"no revolute, continuous or prismatic joint {span}")
    if len(moving) > max_joints:
        raise UrdfError("chain", f"{len(moving)} moving joints {span}, {_beyond(max_joints)}")
    mimics = mimics_of(moving)
    follows = chain_followers(tree, moving, mimics)
    refuse_followers_above(tree, base, follows)
    at_limit: list[str] = []
    positions = held_positions(tree, {joint.name for joint in moving} | set(follows), held or {}, at_limit)
    branches, branch_parents, branch_origins = mimic_branches(tree, moving, follows, positions)

    origins, since_last = [], Placement()
    for joint in path:
        if joint.kind == "fixed":
            since_last = compose(since_last, joint.origin)
        else:
            origins.append(compose(since_last, joint.origin))
            since_last = Placement()
    joined = [*moving, *branches]  # the chain, then the mimic joints hanging off it
    stops = {joint.name for joint in joined}
    held_names: list[str] = []
    carried: list[list[str]] = []
    bodies = [lumped(tree, joint.child, stops, held_names, carried, positions) for joint in joined]
    warnings, physical = _checked_inertials(tree, carried)
    parents = [*range(-1, len(moving) - 1), *branch_parents]
    moved = [body.mass for body, _ in bodies]
    for i in reversed(range(len(joined))):
        if parents[i] >= 0:
            moved[parents[i]] += moved[i]
    warnings += [
        f'URDF joint "{clipped(joint.name, 100)}": moves no mass (M(q) is singular: forward dynamics needs a payload)'
        for joint, mass in zip(moving, moved)
        if mass == 0.0
    ]
    joints = [
        _joint(joint, placement, body, ok)
        for joint, placement, (body, _), ok in zip(joined, [*origins, *branch_origins], bodies, physical)
    ]
    mimics = (*(mimics or (None,) * len(moving)), *(follows[joint.name] for joint in branches))
    model = partial(RobotModel, tuple(joints), gravity=base_gravity(tree, base, positions), flange=since_last,
                    parent=tuple(parents), mimics=mimics, flange_joint=moving[-1].name)  # fmt: skip
    ignored = "off the chain: ignored"
    return _loaded(tree, base, tip, joined, model, "chain", held_names, warnings, carried, ignored, positions, at_limit)


def _loaded(tree, base, tip, moving, model, kind, held, warnings, carried, ignored, positions, at_limit) -> LoadedUrdf:
    """The LoadedUrdf of ``model()`` (a ModelError as a UrdfError of ``kind``), with notes on
    the joints held at a limit by default (``at_limit``, ``held.default_note``) and on the
    invalid inertials of the links ``carried`` leaves out (``ignored``: why they do not matter)."""
    try:
        made = model()
    except ModelError as error:
        raise UrdfError(kind, str(error)) from None
    in_model = {name for names in carried for name in names}
    notes = [
        f"{problem[1]} ({ignored})"
        for name, body in tree.inertials.items()
        if name not in in_model and (problem := inertial_problem(name, body))
    ]
    rotation = tuple(tuple(float(x) for x in row) for row in base_rotation(tree, base, positions))
    links = carried_links(tree, moving, positions)
    matter = {*held, *(joint.name for joint in tree.path_from_root(base))}  # the held joints that place a body
    at = tuple((name, value) for name, value in positions.items() if name in matter and value != 0.0)
    notes = [default_note(tree.joints[name], positions[name]) for name in at_limit if name in matter] + notes
    return LoadedUrdf(made, base, tip, tuple(held), tuple(warnings), tuple(notes), rotation, tree.name, links, at)


def mimics_of(moving: list[UrdfJoint]) -> tuple | None:
    """Per moving joint, the ``Mimic`` its <mimic joint= multiplier= offset=> gives (None:
    not a mimic joint); UrdfError for one following a joint that is not among ``moving``."""
    names = {joint.name for joint in moving}
    mimics = [joint.mimic for joint in moving]
    for joint, mimic in zip(moving, mimics):
        if mimic is not None and mimic.joint not in names:
            raise UrdfError(
                f"{joint.label} <mimic>",
                f"follows {clipped(repr(mimic.joint), 60)}, which is not a moving joint of the model "
                "(name a base_link/tip_link taking it in, or one leaving the mimic joint out)",
            )
    return tuple(mimics) if any(m is not None for m in mimics) else None


def _checked_inertials(tree: UrdfTree, carried: list[list[str]]) -> tuple[list[str], list[bool]]:
    """The warnings of the chain's inertials, and for each moving link whether all it
    carries is physical; UrdfError for an inertial that cannot be used."""
    warnings, physical = [], []
    for names in carried:
        ok = True
        for name in names:
            problem = inertial_problem(name, tree.inertials[name])
            if problem is None:
                continue
            kind, error = problem
            if kind == "refused":
                raise error
            warnings.append(f"{error}; taken as given")
            ok = False
        physical.append(ok)
    return warnings, physical


def base_rotation(tree: UrdfTree, base: str, held=None) -> np.ndarray:
    """base_link's axes in the root link's frame, the joints between them at ``held``'s
    positions (``held.held_positions``), else zero."""
    R = np.eye(3)
    for joint in tree.path_from_root(base):
        R = R @ joint.origin.rotation()
        if (held or {}).get(joint.name, 0.0) != 0.0:
            R = R @ motion(joint, held[joint.name])[:3, :3]
    return R


def base_gravity(tree: UrdfTree, base: str, held=None) -> tuple[float, float, float]:
    """The root link's -z gravity in ``base``'s frame, the joints between them held (``base_rotation``)."""
    g = base_rotation(tree, base, held).T @ np.array([0.0, 0.0, -GRAVITY])
    g[np.abs(g) < 1e-12] = 0.0
    return tuple(float(x) + 0.0 for x in g)


def read_urdf(path, max_chars: int | None = None) -> str:
    """The text of a URDF file, or UrdfError in one line: a regular file (not a device, a
    pipe or a folder) of at most ``max_chars`` bytes (default: the input files' limit) of
    UTF-8 text without control characters (``core.io.text_files``)."""
    try:
        text = read_text_file(path, "URDF file", max_chars)
    except InputFileError as error:
        raise UrdfError("file", clipped(str(error), 250)) from None
    try:
        return checked_text(text, len(text))
    except UrdfError as error:
        raise UrdfError("file", f"{clipped(str(path), 120)}: {error.reason}") from None


def lumped(
    tree: UrdfTree, link: str, stop, held: list[str], carried: list[list[str]], positions=None
) -> tuple[RigidBody, bool]:
    """Everything rigidly attached to ``link`` (joints off the chain held: at ``positions``,
    else zero), up to the chain joint ``stop`` (a name, None, or a set of names), as one body
    in ``link``'s frame; and whether any had an inertial. The names of the joints held are
    appended to ``held``, those of the links with an inertial to ``carried`` as a list."""
    positions = positions or {}
    stops = stop if isinstance(stop, (set, frozenset)) else {stop}
    bodies, stack, names = [], [(link, np.eye(4))], []
    carried.append(names)
    with np.errstate(all="ignore"):  # a non-finite inertial is refused by _checked_inertials
        while stack:
            name, T = stack.pop()
            inertial = tree.inertials[name]
            if inertial is not None:
                names.append(name)
                if not isinstance(inertial, RigidBody):  # unreadable: _checked_inertials refuses it
                    continue
                bodies.append(placed(inertial, T[:3, :3], T[:3, 3]) if name != link else inertial)
            for joint in tree.child_joints[name]:
                if joint.name in stops:
                    continue
                at = T @ joint.origin.matrix()
                if joint.kind != "fixed":
                    held.append(joint.name)
                    at = at @ motion(joint, positions[joint.name]) if positions.get(joint.name, 0.0) else at
                stack.append((joint.child, at))
        return (reduce(combine, bodies) if bodies else RigidBody()), bool(names)


def _joint(joint: UrdfJoint, origin: Placement, body: RigidBody, physical: bool) -> Joint:
    where = f"{joint.label} <limit>"
    limit = joint.element.find("limit")
    if limit is None and joint.kind in ("revolute", "prismatic"):
        raise UrdfError(joint.label, f"a {joint.kind} joint needs <limit lower upper effort velocity>")
    if joint.kind == "continuous":
        lower, upper = CONTINUOUS_LIMITS
    else:
        lower, upper = number(limit, "lower", where, 0.0), number(limit, "upper", where, 0.0)
        if lower > upper:
            raise UrdfError(where, f"lower {lower} > upper {upper}")
    effort, velocity = number(limit, "effort", where, 0.0), number(limit, "velocity", where, 0.0)
    dynamics = joint.element.find("dynamics")
    damping = number(dynamics, "damping", f"{joint.label} <dynamics>", 0.0)
    friction = number(dynamics, "friction", f"{joint.label} <dynamics>", 0.0)
    for what, value, element in (
        ("effort", effort, "limit"),
        ("velocity", velocity, "limit"),
        ("damping", damping, "dynamics"),
        ("friction", friction, "dynamics"),
    ):
        if value < 0.0:
            raise UrdfError(f"{joint.label} <{element}>", f"{what} must be >= 0, got {value}")
    if effort > MAX_TORQUE_LIMIT:  # the model's own sanity cap, as the nodes' parameter: named as URDF names it
        raise UrdfError(where, f"effort must be <= {MAX_TORQUE_LIMIT:g} (sanity cap), got {effort:g}")
    return Joint(
        joint.name,
        link=body,
        position_limits=(lower, upper),
        torque_limit=effort,
        origin=origin,
        axis=joint.axis,
        velocity_limit=velocity,
        friction=Friction(damping, friction),
        kind="prismatic" if joint.kind == "prismatic" else "revolute",
        physical=physical,
    )


def _beyond(max_joints: int) -> str:
    """Why a model of more than ``max_joints`` moving joints is refused, for the one-line error."""
    return (
        f"more than the limit of {max_joints} (the generated dynamics grow with the joints): "
        "load part of it, from a lower base link or to a tip link"
    )


def _load_tree(tree: UrdfTree, base: str, max_joints: int, held: dict[str, float]) -> LoadedUrdf:
    """The whole tree below ``base`` as a LoadedUrdf (see ``whole_tree``)."""
    moving, parents, origins = moving_joints(tree, base)
    where = f"below {clipped(repr(base), 60)}"
    if not moving:
        raise UrdfError("tree", f"no revolute, continuous or prismatic joint {where}")
    if len(moving) > max_joints:
        raise UrdfError("tree", f"{len(moving)} moving joints {where}, {_beyond(max_joints)}")
    stops = {joint.name for joint in moving}
    at_limit: list[str] = []
    positions = held_positions(tree, stops, held, at_limit)  # only joints above base_link (or not below it) are held
    carried: list[list[str]] = []
    bodies = [lumped(tree, joint.child, stops, [], carried) for joint in moving]
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
    mimics = mimics_of(moving)
    gravity = base_gravity(tree, base, positions)
    model = partial(RobotModel, tuple(joints), gravity=gravity, parent=tuple(parents), mimics=mimics)
    ignored = "not moved by the tree: ignored"
    tip = moving[-1].child
    return _loaded(tree, base, tip, moving, model, "tree", (), warnings, carried, ignored, positions, at_limit)
