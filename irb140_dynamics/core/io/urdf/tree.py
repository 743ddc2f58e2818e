"""URDF XML text -> the kinematic tree (links, joints, who hangs from whom), and a chain in it.

Only what dynamics needs is read: joints (type, parent, child, origin, axis, limit,
dynamics, mimic) and link inertials. Visuals, collisions, meshes, transmissions and
gazebo tags are ignored (a <transmission>'s <joint> is not a joint of the tree).

Inertials are read as written, not checked here: the loader checks those its chain
carries (``inertial_problem``), the others do not matter. The input is bounded: at most
``max_chars`` characters (default MAX_URDF_CHARS, or the environment's IRB140_MAX_FILE_BYTES,
as every input file: ``core.io.text_files``), text only, and no walk of the tree recurses.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.io.text_files import MAX_TEXT_BYTES, size_limit
from irb140_dynamics.core.model.joints import Placement
from irb140_dynamics.core.model.rigid_body import (
    MAX_INERTIA,
    MAX_LENGTH,
    MAX_MASS,
    ZERO3,
    ModelError,
    RigidBody,
    Vector3,
    physical_inertia,
    placed,
)
from irb140_dynamics.core.model.tree import Mimic

KINDS = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
MOVING = KINDS[:3]  # the kinds of joint with a position (the model's joints, or held)
MAX_URDF_CHARS = MAX_TEXT_BYTES  # characters of URDF text at most (IRB140_MAX_FILE_BYTES changes it)
PARSE_CHUNK = 1 << 14  # characters the XML parser (and the check for binary data) takes at a time
MAX_LINE = 299  # characters of a refusal line at most
RIGHT_ANGLE_TOLERANCE = 1e-10  # rad: an <origin rpy> angle this close to a multiple of pi/2 is taken as it


class UrdfError(ModelError):
    """A URDF that cannot be used; ``field`` names the element (``URDF joint "x" <limit>``)."""

    def __init__(self, element: str, reason: str):
        element = clipped(element, 100)
        super().__init__(f"URDF {element}", clipped(reason, MAX_LINE - len(element) - 7))


def clipped(text: str, size: int) -> str:
    """``text`` on one line, at most ``size`` characters ("..." where cut)."""
    text = " ".join(str(text).split())
    return text if len(text) <= size else text[: size - 3] + "..."


def listed(names, size: int = 120) -> str:
    """Names joined by ", ", cut to about ``size`` characters with the count of the rest."""
    names = list(names)
    shown, length = [], 0
    for name in names:
        length += len(name) + 2
        if length > size:
            return ", ".join(shown) + f", ... ({len(names) - len(shown)} more)"
        shown.append(name)
    return ", ".join(shown)


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

    @property
    def leader(self) -> str | None:
        """The joint its <mimic joint=...> follows (None: it is no mimic joint, or names none)."""
        element = self.element.find("mimic")
        return None if element is None else element.get("joint")

    @property
    def mimic(self) -> Mimic | None:
        """What its <mimic joint= multiplier= offset=> says (None: it is no mimic joint);
        UrdfError for a <mimic> naming no joint or with a number that is not one."""
        element = self.element.find("mimic")
        if element is None:
            return None
        where = f"{self.label} <mimic>"
        if not element.get("joint"):
            raise UrdfError(where, "names no joint")
        return Mimic(
            element.get("joint"), number(element, "multiplier", where, 1.0), number(element, "offset", where, 0.0)
        )


def in_leader_order(joints: list[UrdfJoint], leaders) -> list[UrdfJoint]:
    """The mimic joints of ``joints`` that follow a joint named in ``leaders``, or one of them
    that does (a mimic of a mimic), each after the joint it follows: in passes over
    ``joints`` in their order, a mimic of a mimic joining in a later pass."""
    known, order = set(leaders), []
    for _ in range(len(joints)):
        before = len(order)
        for joint in joints:
            if joint.name not in known and joint.leader in known:
                known.add(joint.name)
                order.append(joint)
        if len(order) == before:
            break
    return order


@dataclass(frozen=True)
class UrdfTree:
    """Links (their inertial in the link frame, or None), joints, and the tree's shape."""

    name: str
    inertials: dict[str, RigidBody | UrdfError | None]  # as written (unchecked), or why unreadable
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
                raise UrdfError(
                    "tip_link", f"{len(leaves)} leaf links below {clipped(repr(base), 60)}: {listed(leaves)}; name one"
                )
            tip = leaves[0]
        joints, link = [], tip
        while link != base:
            if link not in self.parent_joint:
                raise UrdfError(
                    "tip_link", f"{clipped(repr(tip), 80)} is not below base_link {clipped(repr(base), 80)}"
                )
            joints.append(self.parent_joint[link])
            link = joints[-1].parent
        return base, tip, joints[::-1]

    def leaves(self, link: str) -> list[str]:
        """The leaf links below ``link``, depth first (without recursion)."""
        leaves, stack = [], [link]
        while stack:
            name = stack.pop()
            children = self.child_joints[name]
            if not children:
                leaves.append(name)
            stack += [j.child for j in reversed(children)]
        return leaves

    def path_from_root(self, link: str) -> list[UrdfJoint]:
        """The joints from the root down to ``link``."""
        joints = []
        while link in self.parent_joint:
            joints.append(self.parent_joint[link])
            link = joints[-1].parent
        return joints[::-1]

    def _known(self, what: str, link: str) -> None:
        if link not in self.inertials:
            raise UrdfError(what, f"no link {clipped(repr(link), 80)} in the URDF (links: {listed(self.inertials)})")


def checked_text(text, max_chars: int | None = None) -> str:
    """``text`` if it can be URDF text: a str of at most ``max_chars`` characters (default:
    the input files' limit, ``text_files.size_limit()``) without NUL or other control
    characters (binary data); else UrdfError in one line."""
    max_chars = size_limit(MAX_URDF_CHARS) if max_chars is None else max_chars
    if isinstance(text, (bytes, bytearray)):
        raise UrdfError("document", "bytes given, not text (decode it first)")
    if not isinstance(text, str):
        raise UrdfError("document", f"expected text, got {type(text).__name__}")
    if len(text) > max_chars:
        raise UrdfError(
            "document",
            f"{len(text)} characters, more than the limit of {max_chars} (the environment's IRB140_MAX_FILE_BYTES sets it)",
        )
    for start in range(0, len(text), PARSE_CHUNK):  # in chunks, as the parse (see _parsed)
        binary = _CONTROL.search(text, start, start + PARSE_CHUNK)
        if binary:
            where = f"character {ord(binary.group()):#04x} at {binary.start()}"
            raise UrdfError("document", f"binary data, not text ({where})")
    if not text or text.isspace():
        raise UrdfError("document", "empty")
    return text


_CONTROL = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")


def _parsed(text: str) -> ET.Element:
    """``ET.fromstring(text)``, fed in chunks: the parser holds the interpreter lock for
    each call, and a long text in one call would hold up every other thread meanwhile (a
    node's executor, while a URDF is read in a worker)."""
    parser = ET.XMLParser()
    for start in range(0, len(text), PARSE_CHUNK):
        parser.feed(text[start : start + PARSE_CHUNK])
    return parser.close()


def parse_tree(text: str, max_chars: int | None = None) -> UrdfTree:
    """The tree of a URDF document, or UrdfError naming what is wrong."""
    text = checked_text(text, max_chars)
    try:
        robot = _parsed(text)
    except ET.ParseError as error:
        raise UrdfError("XML", f"does not parse: {error}") from None
    except RecursionError:  # not with expat, kept as a guard: one line whatever the parser
        raise UrdfError("XML", "nested too deeply") from None
    if robot.tag != "robot":
        raise UrdfError("document", f"the root element is <{robot.tag}>, not <robot>")
    inertials: dict[str, RigidBody | UrdfError | None] = {}
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
        raise UrdfError("tree", f"{len(roots)} root links (links no joint leads to): {listed(roots)}")
    reached, stack = set(), [roots[0]]
    while stack:
        link = stack.pop()
        reached.add(link)
        stack += [j.child for j in child_joints[link]]
    if len(reached) != len(inertials):
        loop = [name for name in inertials if name not in reached]
        raise UrdfError("tree", f"a loop through links {listed(loop)}")
    return UrdfTree(robot.get("name", ""), inertials, joints, parent_joint, child_joints, roots[0])


def _name(element: ET.Element, tag: str) -> str:
    name = element.get("name")
    if not name:
        raise UrdfError(f"<{tag}>", "has no name")
    return name


def numbers(
    element: ET.Element | None, attribute: str, count: int, where: str, default=None, finite: bool = True
) -> tuple[float, ...]:
    """``count`` finite numbers (``finite`` False: any) from an attribute like xyz="0 0 0.1", or UrdfError."""
    text = None if element is None else element.get(attribute)
    if text is None:
        if default is None:
            raise UrdfError(where, f"missing {attribute}")
        return tuple(default)
    try:
        values = tuple(float(x) for x in text.split())
    except ValueError:
        values = ()
    if len(values) != count or (finite and not all(map(math.isfinite, values))):
        shown = clipped(text, 60)
        raise UrdfError(where, f'{attribute}="{shown}": expected {count} {"finite " * finite}number{"s" * (count > 1)}')
    return values


def number(
    element: ET.Element | None, attribute: str, where: str, default: float | None = None, finite: bool = True
) -> float:
    return numbers(element, attribute, 1, where, None if default is None else (default,), finite)[0]


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


def _inertial(link: ET.Element, name: str) -> RigidBody | UrdfError | None:
    """The link's inertial in its frame, as written (unchecked); or why it cannot be read."""
    element = link.find("inertial")
    if element is None:
        return None
    where = f'link "{name}" <inertial>'
    try:
        mass = number(element.find("mass"), "value", f"{where} <mass>", finite=False)
        inertia = element.find("inertia")
        moments = tuple(
            number(inertia, key, f"{where} <inertia>", 0.0, finite=False)
            for key in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
        )
        frame = origin(element, where)
    except UrdfError as error:
        return error
    body = RigidBody(mass, ZERO3, moments)
    if frame.is_identity:
        return body
    with np.errstate(all="ignore"):
        return placed(body, frame.rotation(), frame.xyz)


def inertial_problem(name: str, body: RigidBody | UrdfError | None) -> tuple[str, UrdfError] | None:
    """What is wrong with link ``name``'s inertial: ("refused", error) when it cannot be
    used (unreadable, not finite, a negative mass, beyond the sanity caps), ("unphysical",
    error) when it is finite but not physically possible (not positive semi-definite,
    breaking the triangle inequality); None when it is fine."""
    if body is None:
        return None
    if isinstance(body, UrdfError):
        return "refused", body
    if _plainly_fine(body):
        return None
    where = f'link "{clipped(name, 100)}" <inertial>'
    try:
        RigidBody.validated("", body.mass, body.com, body.inertia, physical=False)
    except ModelError as error:
        return "refused", UrdfError(f"{where} <{error.field.split('.')[-1]}>", error.reason)
    try:
        physical_inertia("", body.inertia)
    except ModelError as error:
        return "unphysical", UrdfError(f"{where} <inertia>", error.reason)
    return None


def _plainly_fine(body: RigidBody) -> bool:
    """Whether the inertial is finite, within the caps and physical, decided without NumPy
    for the common case of principal axes (no products of inertia): a tree of thousands of
    links is checked quickly. False: see ``inertial_problem``'s full checks."""
    m, (cx, cy, cz), (xx, yy, zz, xy, xz, yz) = body.mass, body.com, body.inertia
    if xy or xz or yz or not all(map(math.isfinite, (m, cx, cy, cz, xx, yy, zz))):
        return False
    if not (0.0 <= m <= MAX_MASS and math.hypot(cx, cy, cz) <= MAX_LENGTH and max(xx, yy, zz) <= MAX_INERTIA):
        return False
    a, b, c = sorted((xx, yy, zz))
    return a >= 0.0 and a + b >= c


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
