"""A payload on a link of a kinematic tree: the chain of joints it loads, and the rest of the
tree's proven share of their static torques.

Units: kg, m, rad, N m. The payload loads the joints on the path from the base to its link
(``model.carrier``); on a chain that is the whole chain, and nothing here changes it. On a
tree, the joints off that path load the path's joints only through the branches hanging off
a path link ("side branches": the other arm on a torso, a gripper's fingers), statically
through each branch's weight at its centre of mass. For a branch S of mass m_S hanging off
path link k at its root joint's pivot b (a point fixed in link k), its CoM c lies within
r_S of b in every pose of its joints, by the triangle inequality over its links:

    m_S |c - b| <= sum over its links i of m_i (|com_i| + the lengths from b to link i),

each length a joint origin's |xyz|, a DH row's |(a, d)|, or a prismatic joint's largest
displacement within its range. Its static torque at path joint j is that of the mass m_S
at b (a point mass folded into link k: the ``chain`` model) plus m_S (g x z_j) . (c - b),
at most |g x z_j| m_S r_S in size (none for a prismatic joint j: a weight's force along
an axis does not depend on where it hangs; |g x z_j| <= |g|, exact while the joints before
j turn about g). So

    max tau_j over the tree  <=  (the chain's proven bound) + ``slack[j]``,

the sum over the branches below j. The chain's proofs (``family``) then hold on the tree:
what they find is searched again on the whole tree (coordinate ascent from the chain's
worst poses, the branches from 0, every joint of the path and its branches moving; a
coordinate a mimic joint follows too stepped on a grid, its torques being no single
harmonic of it), so every torque found is a real one; the gap left between the two is at
most ``slack`` plus the chain's own. The bound is exact where a branch can stretch its CoM
along g x z_j (an arm turning fully on a joint of horizontal axis) and where nothing hangs
off the path (``moves`` False: the chain is the path itself, as an arm on a fixed torso
with no gripper joints beyond the payload's link; Baxter's fingers add 0.035 N m).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache

import numpy as np

from irb140_dynamics.core.model.rigid_body import RigidBody, combine
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.payload.family import Extremes, PayloadFamily, payload_family
from irb140_dynamics.core.payload.workspace import JointRanges

ROUNDING = 1e-9  # the slack's relative margin for its own rounding


@dataclass(frozen=True, eq=False)
class PayloadPath:
    """``tree``'s payload seen from its link: ``chain``, the joints it loads (their indices
    in the tree's state: ``columns``), each side branch folded into its path link as its
    mass at its pivot; ``slack`` (per chain joint, N m): how much more the side branches'
    poses can add to the size of its static torque."""

    tree: RobotModel
    chain: RobotModel
    columns: np.ndarray  # (n_chain,) int
    slack: np.ndarray  # (n_chain,) N m
    moving: np.ndarray  # (n_tree,) bool: the state's coordinates that move the path or its branches
    _families: dict = field(default_factory=dict, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    @property
    def moves(self) -> bool:
        """Something whose pose changes the path's torques hangs off it (``slack`` > 0): the
        chain is not the tree's path alone (a branch moved by coordinates of its own, or by
        the path's: mimic joints following a path joint, a gripper's other finger)."""
        return self.tree is not self.chain and bool(self.slack.any())

    def family(self, payload: RigidBody) -> PayloadFamily:
        """``payload``'s shape at any mass on the whole tree (its torques, all its joints)."""
        if self.tree is self.chain:
            return payload_family(self.chain, payload)
        key = (tuple(payload.com), tuple(payload.inertia))
        with self._lock:
            family = self._families.get(key)
            if family is None:
                family = self._families[key] = PayloadFamily(
                    *(self.tree.with_payload(RigidBody(m, payload.com, payload.inertia)) for m in (0.0, 1.0))
                )
        return family

    def torques(self, payload: RigidBody, q, qd) -> tuple[np.ndarray, np.ndarray]:
        """(tau0, dtau) of the chain's joints [N m, N m/kg] holding the tree's motion (q, qd), qdd = 0."""
        tau0, dtau = self.family(payload).torques(q, qd)
        return tau0[self.columns], dtau[self.columns]

    def widened(self, payload: RigidBody, load: Extremes) -> Extremes:
        """The chain's worst static torques of ``payload`` (``load``) as the tree's: searched
        again on the whole tree (real torques), bounded by the chain's bounds plus ``slack``."""
        if not self.moves:
            return load
        family, m, n = self.family(payload), payload.mass, self.columns.size
        weights = np.zeros((2 * n, self.tree.n))
        weights[np.arange(n), self.columns], weights[n + np.arange(n), self.columns] = 1.0, -1.0
        warm = np.tile(self._rest, (2 * n, 1))
        warm[:, self.columns] = load.poses

        def torque(Q):
            G0, dG = family.static_torques(Q)
            return G0 + m * dG

        values, poses = self._ranges.climb(torque, weights, warm)
        bounds = load.bounds + np.tile(self.slack, 2)
        return Extremes(values, poses[:, self.columns], np.maximum(bounds, values), poses)

    @cached_property
    def rest(self) -> np.ndarray:
        """The tree's coordinates off the path that load it: its side branches' (none on a chain)."""
        return np.flatnonzero(self.moving & ~np.isin(np.arange(self.tree.n), self.columns))

    def rest_poses(self, load: Extremes) -> tuple[str, ...]:
        """Per chain joint, the rest of the tree in that joint's worst pose (``widened``'s),
        in words: "r1 12.3, r2 -45, finger 0.010 m" (deg; m for a prismatic joint), "" for a
        joint whose torque no pose of the rest changes (``slack`` 0); () when nothing hangs
        off the path."""
        poses = load.largest_tree_pose()
        if poses is None or not self.rest.size:
            return ()
        joints = [self.tree.independent_joints[k] for k in self.rest]
        return tuple(
            ", ".join(
                f"{joint.name} {q:.3f} m" if joint.prismatic else f"{joint.name} {round(math.degrees(q), 1) + 0.0:g}"
                for joint, q in zip(joints, pose[self.rest])
            )
            if share > 0.0
            else ""
            for pose, share in zip(poses, self.slack)
        )

    @cached_property
    def _rest(self) -> np.ndarray:
        """The tree's state with every coordinate at 0 within its range."""
        lower, upper = np.array([j.position_limits for j in self.tree.independent_joints]).T
        return np.clip(0.0, lower, upper)

    @cached_property
    def _ranges(self) -> JointRanges:
        """The tree's joint ranges, the coordinates that do not move the path or its
        branches held at ``_rest``."""
        lower, upper = np.array([j.position_limits for j in self.tree.independent_joints]).T
        lower, upper = np.where(self.moving, lower, self._rest), np.where(self.moving, upper, self._rest)
        sliding = np.array([j.prismatic for j in self.tree.independent_joints], dtype=bool)
        followed = [k for (k, _, _), mimic in zip(self.tree.coordinates, self.tree.mimics or ()) if mimic is not None]
        gridded = np.isin(np.arange(self.tree.n), followed) & (lower < upper)
        return JointRanges(lower, upper, self._rest[None], sliding, gridded)


def payload_path(model: RobotModel) -> PayloadPath:
    """The path of ``model``'s payload (see the module); the chain itself for a chain.
    ValueError in one line for a mimic joint on the path (its coordinate is another's)."""
    if model.is_chain:
        n = model.n
        return PayloadPath(model, model, np.arange(n), np.zeros(n), np.ones(n, dtype=bool))
    return _tree_path(model.with_payload(RigidBody()))  # one path for every payload (each its family)


@lru_cache(maxsize=16)
def _tree_path(model: RobotModel) -> PayloadPath:
    path = [model.carrier]
    while model.parent[path[-1]] >= 0:
        path.append(model.parent[path[-1]])
    path.reverse()
    on_path = set(path)
    mimics = [model.joints[i].name for i in path if model.mimics is not None and model.mimics[i] is not None]
    if mimics:
        raise ValueError(
            f"the payload analysis takes the joints up to the payload's link without mimic joints: "
            f"{mimics[0]!r} is one (hang the payload on a link of an independent joint)"
        )
    children: dict[int, list[int]] = {}
    for i, p in enumerate(model.parent):
        children.setdefault(p, []).append(i)
    ranges = _position_ranges(model)
    lever = _levers(model, path)
    joints, slack, moving = [], np.zeros(len(path)), set(path)
    for place, k in enumerate(path):
        link = model.joints[k].link
        for root in (i for i in children.get(k, []) if i not in on_path):
            branch = _descendants(root, children)
            moving.update(branch)
            mass, moment = _branch_weight(model, root, children, ranges)
            if mass > 0.0:
                link = combine(link, RigidBody(mass, model.joints[root].pre.xyz))
            slack[: place + 1] += lever[: place + 1] * moment * (1 + ROUNDING)
        joints.append(replace(model.joints[k], link=link))
    chain = RobotModel(tuple(joints), model.gravity, model.payload, model.flange, model.smoothing_velocity)
    state_of = {joint: k for k, joint in enumerate(model.independent)}
    coordinates = {model.coordinates[i][0] for i in moving}
    moving_state = np.array([k in coordinates for k in range(model.n)])
    return PayloadPath(model, chain, np.array([state_of[k] for k in path]), slack, moving_state)


def _levers(model, path) -> np.ndarray:
    """Per path joint j, a bound of |g x z_j| [m/s^2] over the poses: 0 for a prismatic
    joint; exact while every revolute joint before it turns about an axis along g (turning
    about g keeps the angle between g and z_j), else |g|."""
    g = np.asarray(model.gravity, dtype=float)
    size, along, R = float(np.linalg.norm(g)), True, np.eye(3)
    levers = []
    for k in path:
        joint = model.joints[k]
        R = R @ joint.pre.rotation()
        axis = R @ np.asarray(joint.turning_axis, dtype=float)
        across = float(np.linalg.norm(np.cross(g, axis)))
        levers.append(0.0 if joint.prismatic else across + ROUNDING * size if along else size)
        along = along and (joint.prismatic or across <= ROUNDING * size)
        R = R @ joint.post.rotation()  # (at q = 0: a turn about g changes no angle to g)
    return np.array(levers)


def _descendants(root: int, children: dict[int, list[int]]) -> list[int]:
    found, stack = [], [root]
    while stack:
        i = stack.pop()
        found.append(i)
        stack.extend(children.get(i, []))
    return found


def _branch_weight(model, root: int, children, ranges) -> tuple[float, float]:
    """(m_S, m_S r_S) of the branch from joint ``root``: its mass, and a proven bound of
    sum m_i |c_i - b| over its links (b: root's pivot), by the lengths from b to each link."""
    mass = moment = 0.0
    stack = [(root, _moved(model.joints[root], ranges[root]))]  # (joint, a bound of |link origin - b|)
    while stack:
        i, reach = stack.pop()
        body = model.joints[i].link
        mass += body.mass
        moment += body.mass * (reach + math.hypot(*body.com))
        for child in children.get(i, []):
            joint = model.joints[child]
            stack.append((child, reach + math.hypot(*joint.pre.xyz) + _moved(joint, ranges[child])))
    return mass, moment


def _moved(joint, limits) -> float:
    """How far the joint moves its link's origin from its pivot, at most [m]."""
    slide = max(abs(limits[0]), abs(limits[1])) if joint.prismatic else 0.0
    return slide + math.hypot(*joint.post.xyz)


def _position_ranges(model) -> list[tuple[float, float]]:
    """Every joint's positions (a mimic joint's: its joint's range mapped)."""
    limits = [j.position_limits for j in model.independent_joints]
    ranges = []
    for k, multiplier, offset in model.coordinates:
        ends = (multiplier * limits[k][0] + offset, multiplier * limits[k][1] + offset)
        ranges.append((min(ends), max(ends)))
    return ranges
