"""The load diagram: the largest payload mass the arm holds at rest in every pose, per
position of the payload's centre of mass, as vendors draw it (Z along the flange axis, L
off it).

Units: kg, m, rad, N m (N for a prismatic joint). The flange frame is the one
``payload.com`` is given in. A CoM at height z on the flange's z axis and distance l off
it may point in any direction about the axis (how the tool is turned is not known), so the
mass must hold for every direction phi too: the CoM (l cos phi, l sin phi, z). The
direction is one more joint: ``pivoted`` adds a massless revolute joint about the flange's
z axis, turning over [-pi, pi], and the payload sits at (l, 0, z) in its frame; its own
torque is not limited. The search takes it as an angle; the proof covers every pose AND
every direction at once without one: at a pose a torque is A + X cos(phi) + Y sin(phi),
at most A + |(X, Y)| (see ``family.PayloadFamily.direction``), bounded over the poses, and
a wrist joint that only turns the CoM about the flange axis drops out with it
(``harmonic.without_wrist``).

At each point the payload's torques are affine in its mass (see ``family``). Dinkelbach's
iteration over searched poses gives the mass m* at which a real pose reaches a limit (an
upper bound of the true maximum); the proof then shows that (1 - margin) m* holds in every
pose: every limited joint's worst static torque there is proven below its limit (a
decision, far cheaper than the exact maximum). A proof that finds a worse pose than the
search hands it back to Dinkelbach; one whose budget runs out is tried again with the next
of MARGINS (ROUNDS proofs at most). Where it still fails the point is unproven, and its
mass the one the search found: no more can hold. Once per diagram the arm without payload is
proven within its limits too: the torques being affine in the mass, every mass below one
proven to hold then holds as well (else no point is called proven).

The forms of the proof are linear in the payload's mass and first moment, so they are
made once per arm (at 0 kg, and 1 kg at the origin, at x = 1 m and at z = 1 m) and mixed
per point in interval arithmetic (rigorous).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields, replace

import numpy as np

from irb140_dynamics.core.dynamics import gravity_batch
from irb140_dynamics.core.model.joints import Joint, Placement
from irb140_dynamics.core.model.rigid_body import MAX_MASS, RigidBody
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.payload.family import PayloadFamily
from irb140_dynamics.core.payload.limits import limit_values, smallest_max_payload
from irb140_dynamics.core.payload.proof.harmonic import MAX_JOINTS, StaticForms
from irb140_dynamics.core.payload.stop import ran_out
from irb140_dynamics.core.payload.workspace import JointRanges

MARGINS = (0.005, 0.015)  # the proof aims at (1 - margin) of the mass the search finds; the next if it fails
ROUNDS = 4  # proofs per point (each after Dinkelbach from the worse poses the last one found, or with the next margin)
PROOF_SHARE = 24.0  # of ``certify.EVALUATIONS`` per proof: a heavy arm's own torques leave a payload little room
MOST_JOINTS = MAX_JOINTS  # moving joints the harmonic proof takes (and the direction: 3^10 terms; intervals beyond)
DIRECTION = "load_direction"  # the name of the joint that turns the CoM about the flange axis
SEARCH_RTOL = 1e-9  # the searches' ascent stops gaining this share of the torque: far below MARGINS (a third of the sweeps of 1e-12)


@dataclass(frozen=True, eq=False)
class DiagramPoint:
    """One CoM position: z, l [m]; ``mass`` [kg] proven to hold in every pose and direction
    (``proven``), else the mass the search found (nothing above it holds; nan: none; inf:
    no limited joint is loaded); the joint at its limit (index; None: none); why unproven;
    ``found``, the mass at which a pose found brings that joint to its limit (no more holds)."""

    z: float
    l: float
    mass: float
    proven: bool
    joint: int | None
    reason: str = ""
    found: float = math.nan


@dataclass(frozen=True, eq=False)
class LoadDiagram:
    """The diagram over the grid z (Z,) x l (L,): ``points`` row by row (z outer)."""

    joint_names: tuple[str, ...]
    limits: np.ndarray  # (n,) N m the masses are proven against (inf: none)
    z: np.ndarray
    l: np.ndarray
    points: tuple[DiagramPoint, ...]

    def masses(self) -> np.ndarray:
        """The masses as a (Z, L) array [kg]."""
        return np.array([p.mass for p in self.points], dtype=float).reshape(self.z.size, self.l.size)

    @property
    def proven_share(self) -> float:
        return sum(p.proven for p in self.points) / len(self.points)


def pivoted(model: RobotModel) -> RobotModel:
    """The model with one more joint: a massless revolute joint at the flange, about its z
    axis, over [-pi, pi]; the flange is that joint's frame (the payload turns with it)."""
    name = DIRECTION
    while name in model.joint_names:
        name += "_"
    turn = Joint(name, origin=model.flange, axis=(0.0, 0.0, 1.0), position_limits=(-math.pi, math.pi))
    return replace(model, joints=model.joints + (turn,), flange=Placement(), payload=RigidBody())


class _Shapes:
    """Payload families on the pivoted arm for CoM (l, 0, z), their forms mixed from four."""

    def __init__(self, arm: RobotModel):
        self.arm = arm
        basis = [RigidBody(0.0), RigidBody(1.0), RigidBody(1.0, (1.0, 0.0, 0.0)), RigidBody(1.0, (0.0, 0.0, 1.0))]
        forms = [StaticForms.of(arm.with_payload(body), MOST_JOINTS + 1) for body in basis]
        self.forms = None if forms[0] is None else forms

    def family(self, z: float, l: float) -> PayloadFamily:
        shape = RigidBody(1.0, (l, 0.0, z))
        given = None
        if self.forms is not None:
            empty, origin, x, up = self.forms
            given = (empty, _mixed(origin, [(x, l), (up, z)]))
        direction = self.arm.n - 1  # a whole turn: the worst direction is A + |(X, Y)|
        return PayloadFamily(self.arm.with_payload(RigidBody(0.0)), self.arm.with_payload(shape), given, direction)


def _mixed(origin: StaticForms, steps) -> StaticForms:
    """origin + sum of k (other - origin) over the steps (other, k): forms at another CoM."""
    torque, omega = origin.torque, origin.omega
    for other, k in steps:
        if k:  # (a product with 0 is the float 0, not a sum)
            torque = torque + (other.torque - origin.torque) * k
            omega = tuple(w + (b - a) * k for w, a, b in zip(omega, origin.omega, other.omega))
    return StaticForms(torque, omega, origin.gravity_norm, origin.sliding)


def load_diagram(
    model: RobotModel,
    limits: Sequence[float],
    z: Sequence[float],
    l: Sequence[float],
    progress: Callable[[int, int], None] | None = None,
    workers: int = 1,
) -> LoadDiagram:
    """The load diagram of ``model`` against the torque limits (n,) [N m, inf: none] on the
    grid z x l [m] (see the module). ``progress(done, total)`` after each row of z;
    ``workers`` > 1: the rows shared among that many processes (forked)."""
    L = limit_values(limits, model.n)
    z, l = np.asarray(z, dtype=float), np.asarray(l, dtype=float)
    job = (model, L, l)
    rows: list[list[DiagramPoint]] = [[] for _ in z]
    _arm_of(model)  # (made before the workers fork: they inherit it, compiled)
    alone = _alone(model, np.append(L, np.inf))
    if workers > 1 and z.size > 1:
        import multiprocessing

        _JOBS[0] = job  # the forked workers find it here (a model's compiled kernels do not pickle)
        pool = multiprocessing.get_context("fork").Pool(min(workers, z.size), _quiet)
        try:
            for done, (i, row) in enumerate(pool.imap_unordered(_row, list(enumerate(z))), 1):
                rows[i] = row
                if progress is not None:
                    progress(done, z.size)
            pool.close()
        except BaseException:
            pool.terminate()
            raise
        finally:
            pool.join()
            _JOBS[0] = None
    else:
        for i, zi in enumerate(z):
            rows[i] = _row((i, zi), job)[1]
            if progress is not None:
                progress(i + 1, z.size)
    if not alone:  # a mass proven to hold, but not the masses below it
        why = "the arm alone is not proven within its limits in every pose"
        rows = [[replace(p, proven=False, reason=p.reason or why) for p in row] for row in rows]
    return LoadDiagram(model.joint_names, L, z, l, tuple(p for row in rows for p in row))


def _quiet() -> None:
    """A worker leaves Ctrl-C to its parent, which ends the pool, and ends at once when
    told to (not by a handler the parent had installed)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


_JOBS: list = [None]
_ARMS: dict = {}  # per process: the pivoted arm and its forms, per arm (the last ARMS_KEPT)
_PROVEN: dict = {}  # per process and arm: cold-started points and the arm alone's proof, per limits
ARMS_KEPT, POINTS_KEPT = 2, 64


def _arm_of(model: RobotModel):
    """(model, its pivoted arm's shapes, that arm's ranges), made once per arm (the same
    joints, flange and gravity: its payload is replaced anyway)."""
    key = _arm_key(model)
    if key not in _ARMS:
        while len(_ARMS) >= ARMS_KEPT:
            _PROVEN.pop(_ARMS.pop(next(iter(_ARMS)))[0], None)
        arm = pivoted(model)
        _ARMS[key] = (key, model, _Shapes(arm), JointRanges.of(arm))
    return _ARMS[key][1:]


def _arm_key(model: RobotModel) -> tuple:
    return tuple(getattr(model, f.name) for f in fields(model) if f.name != "payload")


def _remembered(model: RobotModel, what: tuple, make):
    """make(), remembered per arm and ``what`` (a result the deadline cut short is not)."""
    known = _PROVEN.setdefault(_arm_key(model), {})
    if what not in known:
        result = make()
        if ran_out():
            return result
        while len(known) >= POINTS_KEPT:
            known.pop(next(iter(known)))
        known[what] = result
    return known[what]


def _holds_alone(family: PayloadFamily, ranges: JointRanges, L: np.ndarray) -> bool:
    """Is the arm without payload proven within its limits in every pose? Then, torques
    being affine in the mass, every mass below one proven to hold holds too."""
    limited = np.flatnonzero(np.isfinite(np.tile(L, 2)))
    ceiling = np.tile(L, 2)
    found = family.search(0.0, ranges)
    if np.any(found[0][limited] > ceiling[limited]):  # a real pose beyond a limit: no proof can hold
        return False
    proof = family.extremes(0.0, ranges, rows=limited, found=found, ceiling=ceiling, share=PROOF_SHARE)
    return bool(np.all(proof.bounds[limited] <= ceiling[limited]))


def _alone(model: RobotModel, L_arm: np.ndarray) -> bool:
    """``_holds_alone`` of ``model``'s pivoted arm, remembered."""
    _, shapes, ranges = _arm_of(model)
    return _remembered(model, ("alone", L_arm.tobytes()), lambda: _holds_alone(shapes.family(0.0, 0.0), ranges, L_arm))


def _cold_point(model: RobotModel, L_arm: np.ndarray, z: float, l: float):
    """``_point`` at (z, l) with no warm start, remembered: (the point, its poses)."""
    _, shapes, ranges = _arm_of(model)

    def make():
        return _point(shapes.family(z, l), ranges, L_arm, None, z, l)

    point, poses = _remembered(model, ("point", L_arm.tobytes(), np.array([z, l]).tobytes()), make)
    return point, None if poses is None else poses.copy()


def _row(item, job=None):
    """(i, the points at z for every l), warm-starting each point from the last."""
    i, z = item
    model, L, l = _JOBS[0] if job is None else job
    _, shapes, ranges = _arm_of(model)
    L_arm = np.append(L, np.inf)
    warm, points = None, []
    for lk in l:
        if warm is None:
            point, warm = _cold_point(model, L_arm, float(z), float(lk))
        else:
            point, warm = _point(shapes.family(float(z), float(lk)), ranges, L_arm, warm, float(z), float(lk))
        points.append(point)
    return i, points


def _point(family: PayloadFamily, ranges: JointRanges, L: np.ndarray, warm, z: float, l: float):
    """The diagram's point (z, l), and the poses to warm the next point's search with."""
    n = family.empty.n
    G0, dG = family.static_torques(ranges.samples)
    limited = np.flatnonzero(np.isfinite(np.tile(L, 2)))
    weights = np.vstack([np.eye(n), -np.eye(n)])[limited]
    best = smallest_max_payload(family, ranges.samples, L, G0, dG)
    poses = warm
    if poses is not None:
        from_warm = smallest_max_payload(family, poses, L)
        best = from_warm if _below(from_warm.mass, best.mass) else best
    margin = iter(MARGINS)
    m, fraction = math.nan, 1 - next(margin)
    for _ in range(ROUNDS):
        while math.isfinite(best.mass):  # Dinkelbach, on the limited joints' torques only
            torque = _static_torque(family, min(best.mass, MAX_MASS))
            sampled = G0 + min(best.mass, MAX_MASS) * dG
            _, poses = ranges.maximize(torque, weights, sampled, warm=poses, rtol=SEARCH_RTOL)
            candidate = smallest_max_payload(family, poses, L)
            if not _below(candidate.mass, best.mass * (1 - 1e-12)):
                break
            best = candidate
        if math.isnan(best.mass):
            why = "a pose exceeds a limit without any payload"
            return DiagramPoint(z, l, math.nan, False, best.joint, why, math.nan), poses
        if math.isinf(best.mass):
            return DiagramPoint(z, l, math.inf, False, None, "no limited joint is loaded", math.inf), poses
        m = min(best.mass, MAX_MASS) * fraction
        ceiling = np.tile(L, 2)
        every = np.repeat(poses[:1], 2 * n, axis=0)  # rows not proven: a real pose's torque
        every[limited] = poses
        found = (np.einsum("kn,kn->k", _static_torque(family, m)(every), np.vstack([np.eye(n), -np.eye(n)])), every)
        proof = family.extremes(m, ranges, rows=limited, found=found, ceiling=ceiling, share=PROOF_SHARE)
        if np.all(proof.bounds[limited] <= ceiling[limited]):
            return DiagramPoint(z, l, m, True, best.joint, "", best.mass), poses
        candidate = smallest_max_payload(family, proof.poses[limited], L)
        if _below(candidate.mass, best.mass * (1 - 1e-12)):
            best, poses = candidate, proof.poses[limited]  # the search missed a worse pose
            continue
        fraction = 1 - next(margin, math.nan)  # the bounds did not close: aim lower
        if math.isnan(fraction):
            break
    reason = f"the proof's budget ran out at {m:.4g} kg (no more than {best.mass:.4g} kg holds)"
    return DiagramPoint(z, l, best.mass, False, best.joint, reason, best.mass), poses


def _static_torque(family: PayloadFamily, m: float):
    """Q -> the static torques at poses Q (N, n) with the payload at m kg: one pass."""
    carrying = family.unit.with_payload(replace(family.unit.payload, mass=float(m)))
    return lambda Q: gravity_batch(carrying, Q)


def _below(a: float, b: float) -> bool:
    return a < b or (math.isnan(a) and not math.isnan(b))


@dataclass(frozen=True, eq=False)
class PointCheck:
    """Whether a payload of ``mass`` kg with its CoM at (z, l) [m] lies inside the proven
    diagram: ``inside`` only when proven to hold in every pose and direction; ``proven``
    the largest mass proven at the point (nan: none), ``found`` the mass at which a pose
    found brings ``joint`` (its name) to its limit; why not, when not."""

    mass: float
    z: float
    l: float
    inside: bool
    proven: float
    found: float
    joint: str | None
    reason: str = ""

    @property
    def margin(self) -> float:
        """kg: inside, the mass proven to hold beyond ``mass`` (at least this much more
        holds); outside, how far ``mass`` is beyond what holds (negative): beyond ``found``
        where a pose exceeds a limit, else beyond what is proven."""
        if self.inside:
            return max(self.proven - self.mass, 0.0)
        if self.mass >= self.found:
            return self.found - self.mass
        return self.proven - self.mass if math.isfinite(self.proven) else math.nan

    def sentence(self) -> str:
        """The check in one line."""
        at = f"{self.mass:g} kg at Z {self.z:g} m, L {self.l:g} m"
        joint = f"limiting joint {self.joint}" if self.joint else "no limiting joint"
        known = [f"{self.proven:.3f} kg proven"] if math.isfinite(self.proven) else []
        if math.isfinite(self.found):
            known.append(f"a pose reaches the limit at {self.found:.3f} kg")
        detail = f" ({'; '.join(known)})" if known else ""
        if self.inside:
            return (
                f"inside: {at} holds in every pose and direction (proven); margin {self.margin:.3f} kg{detail}; {joint}"
            )
        margin = f"margin {self.margin:.3f} kg" if math.isfinite(self.margin) else "no margin"
        return f"outside: {at} {self.reason}; {margin}{detail}; {joint}"


def check_point(model: RobotModel, limits: Sequence[float], mass: float, z: float, l: float) -> PointCheck:
    """Is ``mass`` [kg] with its CoM at (z, l) [m] inside the load diagram of ``model``
    against ``limits`` (n,) [N m, inf: none], proven for that point (as ``load_diagram``
    proves a grid point, then, where the mass lies between the proven mass and the one a
    pose reaches a limit with, the proof at ``mass`` itself)?"""
    L = limit_values(limits, model.n)
    _, shapes, ranges = _arm_of(model)
    L_arm = np.append(L, np.inf)
    point, _ = _cold_point(model, L_arm, float(z), float(l))
    name = None if point.joint is None else model.joint_names[point.joint]
    proven = point.mass if point.proven else math.nan
    result = PointCheck(float(mass), float(z), float(l), False, proven, point.found, name)
    if math.isnan(point.found):
        return replace(result, reason=point.reason or "no mass holds there")
    if mass >= point.found:
        return replace(result, reason=f"exceeds {name}'s limit in a pose found")
    alone = _alone(model, L_arm)
    if point.proven and alone and mass <= point.mass:  # torques affine in the mass: every lighter one holds
        return replace(result, inside=True)
    if _proven_at(shapes.family(float(z), float(l)), ranges, L_arm, float(mass)):
        return replace(result, inside=True, proven=max(float(mass), proven if alone else math.nan))
    return replace(result, reason="is not proven to hold in every pose (too near the limit for the proof)")


def _proven_at(family: PayloadFamily, ranges: JointRanges, L: np.ndarray, mass: float) -> bool:
    """Is every limited joint's worst static torque with the payload at ``mass`` proven
    within its limit, over every pose and direction?"""
    ceiling = np.tile(L, 2)
    limited = np.flatnonzero(np.isfinite(ceiling))
    found = family.search(mass, ranges)
    if np.any(found[0][limited] > ceiling[limited]):
        return False
    proof = family.extremes(mass, ranges, rows=limited, found=found, ceiling=ceiling, share=PROOF_SHARE)
    return bool(np.all(proof.bounds[limited] <= ceiling[limited]))
