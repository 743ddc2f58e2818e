"""URDF XML text -> the kinematic tree (links, joints, who hangs from whom), and a chain in it.

Only what dynamics needs is read: joints (type, parent, child, origin, axis, limit,
dynamics, mimic) and link inertials. Visuals, collisions, meshes, transmissions and
gazebo tags are ignored (a <transmission>'s <joint> is not a joint of the tree).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from irb140_dynamics.core.model.joints import Placement
from irb140_dynamics.core.model.rigid_body import ModelError, RigidBody, Vector3, placed

KINDS = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
RIGHT_ANGLE_TOLERANCE = 1e-10  # rad: an <origin rpy> angle this close to a multiple of pi/2 is taken as it


class UrdfError(ModelError):
    """A URDF that cannot be used; ``field`` names the element (``URDF joint "x" <limit>``)."""

    def __init__(self, element: str, reason: str):
        super().__init__(f"URDF {element}", reason)


@dataclass(frozen=True)
class UrdfJoint:
    name: str
    kind: str
    parent: str
    child: str
    origin: Placement
    axis: Vector3
    element: ET.Element  # for <limit>, <dynamics>, <mimic>

    @property
    def label(self) -> str:
        return f'joint "{self.name}"'


@dataclass(frozen=True)
class UrdfTree:
    """Links (their inertial in the link frame, or None), joints, and the tree's shape."""

    name: str
    inertials: dict[str, RigidBody | None]
    joints: dict[str, UrdfJoint]
    parent_joint: dict[str, UrdfJoint]  # link -> the joint whose child it is
    child_joints: dict[str, list[UrdfJoint]]  # link -> joints whose parent it is
    root: str

    def chain(self, base: str | None = None, tip: str | None = None) -> tuple[str, str, list[UrdfJoint]]:
        """(base, tip, joints from base to tip); base defaults to the root, tip to the only
        leaf below base."""
        base = base or self.root
        self._known("base_link", base)
        if tip:
            self._known("tip_link", tip)
        else:
            leaves = self.leaves(base)
            if len(leaves) != 1:
                raise UrdfError("tip_link", f"{len(leaves)} leaf links below {base!r}: {', '.join(leaves)}; name one")
            tip = leaves[0]
        joints, link = [], tip
        while link != base:
            if link not in self.parent_joint:
                raise UrdfError("tip_link", f"{tip!r} is not below base_link {base!r}")
            joints.append(self.parent_joint[link])
            link = joints[-1].parent
        return base, tip, joints[::-1]

    def leaves(self, link: str) -> list[str]:
        children = self.child_joints[link]
        return [link] if not children else [leaf for j in children for leaf in self.leaves(j.child)]

    def _known(self, what: str, link: str) -> None:
        if link not in self.inertials:
            raise UrdfError(what, f"no link {link!r} in the URDF (links: {', '.join(self.inertials)})")


def parse_tree(text: str) -> UrdfTree:
    """The tree of a URDF document, or UrdfError naming what is wrong."""
    if not isinstance(text, str) or not text.strip():
        raise UrdfError("document", "empty")
    try:
        robot = ET.fromstring(text)
    except ET.ParseError as error:
        raise UrdfError("XML", f"does not parse: {error}") from None
    if robot.tag != "robot":
        raise UrdfError("document", f"the root element is <{robot.tag}>, not <robot>")
    inertials: dict[str, RigidBody | None] = {}
    for element in robot.findall("link"):
        name = _name(element, "link")
        if name in inertials:
            raise UrdfError(f'link "{name}"', "defined twice")
        inertials[name] = _inertial(element, name)
    joints: dict[str, UrdfJoint] = {}
    parent_joint: dict[str, UrdfJoint] = {}
    child_joints: dict[str, list[UrdfJoint]] = {name: [] for name in inertials}
    for element in robot.findall("joint"):  # direct children only: not <transmission>'s
        joint = _joint(element, inertials)
        if joint.name in joints:
            raise UrdfError(joint.label, "defined twice")
        if joint.child in parent_joint:
            other = parent_joint[joint.child].name
            raise UrdfError(f'link "{joint.child}"', f'has two parents: joints "{other}" and "{joint.name}"')
        joints[joint.name] = parent_joint[joint.child] = joint
        child_joints[joint.parent].append(joint)
    roots = [name for name in inertials if name not in parent_joint]
    if not inertials:
        raise UrdfError("document", "no <link>")
    if not roots:
        raise UrdfError("tree", "a loop: every link is the child of a joint")
    if len(roots) > 1:
        raise UrdfError("tree", f"{len(roots)} root links (links no joint leads to): {', '.join(roots)}")
    reached, stack = set(), [roots[0]]
    while stack:
        link = stack.pop()
        reached.add(link)
        stack += [j.child for j in child_joints[link]]
    if len(reached) != len(inertials):
        loop = [name for name in inertials if name not in reached]
        raise UrdfError("tree", f"a loop through links {', '.join(loop)}")
    return UrdfTree(robot.get("name", ""), inertials, joints, parent_joint, child_joints, roots[0])


def _name(element: ET.Element, tag: str) -> str:
    name = element.get("name")
    if not name:
        raise UrdfError(f"<{tag}>", "has no name")
    return name


def numbers(element: ET.Element | None, attribute: str, count: int, where: str, default=None) -> tuple[float, ...]:
    """``count`` finite numbers from an attribute like xyz="0 0 0.1", or UrdfError."""
    text = None if element is None else element.get(attribute)
    if text is None:
        if default is None:
            raise UrdfError(where, f"missing {attribute}")
        return tuple(default)
    try:
        values = tuple(float(x) for x in text.split())
    except ValueError:
        values = ()
    if len(values) != count or not all(map(math.isfinite, values)):
        raise UrdfError(where, f'{attribute}="{text}": expected {count} finite number{"s" * (count > 1)}')
    return values


def number(element: ET.Element | None, attribute: str, where: str, default: float | None = None) -> float:
    return numbers(element, attribute, 1, where, None if default is None else (default,))[0]


def origin(parent: ET.Element, where: str) -> Placement:
    element = parent.find("origin")
    where = f"{where} <origin>"
    rpy = numbers(element, "rpy", 3, where, (0.0,) * 3)
    return Placement(numbers(element, "xyz", 3, where, (0.0,) * 3), tuple(map(right_angle_snapped, rpy)))


def right_angle_snapped(angle: float) -> float:
    """A multiple of pi/2 if ``angle`` is within RIGHT_ANGLE_TOLERANCE of it, else ``angle``.

    Files write pi/2 as 1.57079632679 (5e-12 off): taken as exact, its cosine is 0 and the
    generated kernels drop the terms it multiplies (about 10 % of the UR5's RNEA)."""
    quarter_turns = round(angle / (math.pi / 2))
    exact = quarter_turns * (math.pi / 2)
    return exact if abs(angle - exact) < RIGHT_ANGLE_TOLERANCE else angle


def _inertial(link: ET.Element, name: str) -> RigidBody | None:
    element = link.find("inertial")
    if element is None:
        return None
    where = f'link "{name}" <inertial>'
    mass = number(element.find("mass"), "value", f"{where} <mass>")
    inertia = element.find("inertia")
    moments = tuple(
        number(inertia, key, f"{where} <inertia>", 0.0) for key in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
    )
    frame = origin(element, where)
    try:  # checks the mass, positive semi-definiteness and the triangle inequality
        body = RigidBody.validated("inertial", mass, inertia=moments)
    except ModelError as error:
        raise UrdfError(f"{where} <{error.field.split('.')[-1]}>", error.reason) from None
    return placed(body, frame.rotation(), frame.xyz)


def _joint(element: ET.Element, links) -> UrdfJoint:
    name = _name(element, "joint")
    where = f'joint "{name}"'
    kind = element.get("type")
    if kind not in KINDS:
        raise UrdfError(where, f"type {kind!r} is not one of {', '.join(KINDS)}")
    ends = []
    for tag in ("parent", "child"):
        link = element.find(tag)
        link = None if link is None else link.get("link")
        if link not in links:
            raise UrdfError(f"{where} <{tag}>", "missing" if link is None else f"no link {link!r}")
        ends.append(link)
    axis = numbers(element.find("axis"), "xyz", 3, f"{where} <axis>", (1.0, 0.0, 0.0))
    norm = math.hypot(*axis)
    if kind in ("revolute", "continuous", "prismatic") and norm < 1e-9:
        raise UrdfError(f"{where} <axis>", f"xyz={list(axis)} is not a direction")
    axis = tuple(x / norm for x in axis) if norm > 0 and abs(norm - 1.0) > 1e-15 else axis
    return UrdfJoint(name, kind, ends[0], ends[1], origin(element, where), axis, element)
