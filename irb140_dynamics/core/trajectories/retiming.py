"""The time-optimal timing of a trajectory's path under the model's torque, velocity and
acceleration limits, with its friction, armature and payload.

Along the path q(s) (see ``path``), with x = sd^2 and u = sdd:

    qd = q' sd,    qdd = q' u + q'' x,
    tau = a u + b x + c + tau_f,   a = M q',  b = M q'' + C(q, q') q',  c = g(q)

(a, b, c from ``rnea``: armature and payload included). Friction tau_f,j = sign(q'_j)
(viscous_j |q'_j| sd + coulomb_j tanh(|q'_j| sd / v_s)) for sd >= 0. It is bounded soundly by
terms linear in x: Coulomb between 0 and coulomb_j (between -coulomb_j and coulomb_j where q'_j
changes sign at a neighbouring grid point); the viscous sqrt(x) from above by its
tangent at x0 (the previous round's x) and from below by its chord over [0, X] (X: the
velocity cap, which x then may not pass). So every limit is a row linear in (u, x), and
``topp`` finds the time-optimal profile on the grid.

The output has a point at every grid point (the input's points among them, in order) with
its time, its position on the path and its velocity qd = q' sd, and no accelerations, so
that the controller interpolates cubic: a cubic matched to positions and velocities at both
ends reproduces a step of constant sdd exactly on a straight path, and to O(h^4) on a curved
one. A quintic, matched to one acceleration per point as well, cannot follow the jumps of
sdd where the time-optimal profile switches (bang-bang): between points it overshoots by
up to 37 % of the jump (its acceleration basis dips to -0.374). With ``accelerations`` the
points carry them anyway (u the mean of the steps either side, 0 at a stop inside the path)
and the verification below lowers the limits around the switches until the quintic keeps
within them, at the cost of time (see docs/trajectories.md).

The result is played as the controller would and sampled ``VERIFY`` times finer than the
grid: where any limit is exceeded between grid points (the rows only hold at grid points),
the limits at that step's grid points (and ``WINDOW`` either side) are lowered by the
excess and the profile computed again, until nothing is exceeded. The first round uses
``MARGIN`` of the limits, which mostly spares a second.

A path no timing makes feasible (holding a pose on it needs more than a torque limit) is
refused naming the joint, the input point and the amount.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core.dynamics import gravity_batch, rnea_batch
from irb140_dynamics.core.model.friction import JointFriction
from irb140_dynamics.core.model.robot_model import RobotModel

from .check import profiles
from .interpolation import sample_times, spline
from .limits import Limits, trajectory_limits
from .message import Trajectory, TrajectoryError
from .path import PathGrid, path_grid, steps_per_segment
from .topp import max_velocity_curve, topp

GRID = 1000  # grid steps over the path, about
VERIFY = 10  # samples per output interval when verifying
ROUNDS = 20  # verification rounds at most
SHRINK = 0.999  # limits lowered a little more than the excess, so that a round ends it
MARGIN = 0.995  # the limits' share the first round uses: between grid points they may be exceeded a little
REACH = 2  # grid points on which an interval's playback depends, either side (the quintic's u: 2)
WINDOW = 1  # grid points either side of an interval over a limit lowered with it


@dataclass(frozen=True, eq=False)
class Retimed:
    """The re-timed trajectory, the grid it was computed on, x = sd^2 and u = sdd there, the
    worst use of any limit (value / limit) on the verification samples, and the rounds."""

    trajectory: Trajectory
    grid: PathGrid
    x: np.ndarray
    u: np.ndarray
    worst: float
    rounds: int

    @property
    def duration(self) -> float:
        return self.trajectory.duration


@dataclass(frozen=True, eq=False)
class _Dynamics:
    a: np.ndarray  # (G+1, n): M q'
    b: np.ndarray  # M q'' + C(q, q') q'
    c: np.ndarray  # g(q)


def retime(
    model: RobotModel,
    tr: Trajectory,
    limits: Limits | None = None,
    grid: int = GRID,
    steps=None,
    verify: int = VERIFY,
    rounds: int = ROUNDS,
    accelerations: bool = False,
) -> Retimed:
    """The time-optimal re-timing of ``tr``'s path on ``model`` (payload included), from rest
    to rest; ``steps`` (per input segment) overrides ``grid``. ``accelerations``: give the
    points accelerations too (the controller then interpolates quintic; see the module)."""
    limits = trajectory_limits(model) if limits is None else limits
    pg = path_grid(tr, steps_per_segment(tr, grid) if steps is None else np.asarray(steps))
    dyn = _dynamics(model, pg)
    _refuse_static(model, pg, dyn, limits, tr)
    factor = np.full(len(pg.s), MARGIN)
    floor = _static_share(model, pg, dyn, limits)
    x0 = previous = ratio = solved = solved_factor = None
    worst, used = np.inf, 0
    while used < rounds:
        used += 1
        if solved is None:  # the first round, or the one with the friction's tangents at x
            x, u, solved = _profile(model, pg, dyn, limits, factor, x0, floor)
        else:  # only where the limits were lowered
            changed = np.flatnonzero(factor != solved_factor)
            x, u, solved = _profile(model, pg, dyn, limits, factor, x0, floor, solved, changed)
        solved_factor = factor.copy()
        out, _ = _output(pg, x, u, tr, accelerations)
        again = _changed(x, previous)  # an interval whose ends kept their x plays as before
        fresh = _ratios(model, out, limits, verify, again)
        ratio = fresh if again is None else np.where(np.isin(np.arange(len(fresh)), again), fresh, ratio)
        previous = x
        worst = float(ratio.max())
        if worst <= 1.0 and (x0 is not None or model.friction is None):
            break
        if x0 is None and model.friction is not None:
            x0, solved = x, None  # the viscous friction's tangents at this profile: every row changes
        shrink = np.ones(len(pg.s))
        for i in np.flatnonzero(ratio > 1.0):  # the interval's points and WINDOW either side
            lo, hi = max(i - WINDOW, 0), min(i + 1 + WINDOW, len(shrink) - 1)
            shrink[lo : hi + 1] = np.minimum(shrink[lo : hi + 1], SHRINK / ratio[i])
        factor = factor * shrink
    if worst > 1.0:
        raise TrajectoryError(
            f"no timing kept every limit between grid points within {rounds} rounds (worst: {100 * worst:.2f} % "
            "of a limit): try a finer grid"
        )
    return Retimed(out, pg, x, u, worst, used)


def _dynamics(model: RobotModel, pg: PathGrid) -> _Dynamics:
    """a, b, c at every grid point, with the path's derivatives on the step ahead (the right)."""
    q1, q2 = pg.q1[1], pg.q2[1]
    c = gravity_batch(model, pg.q)
    a = rnea_batch(model, pg.q, np.zeros_like(q1), q1) - c
    tau = rnea_batch(model, pg.q, q1, q2) - c
    return _Dynamics(a, tau if model.friction is None else tau - model.friction.torques(q1), c)


def _friction(model) -> JointFriction:
    """The friction of the coordinates (a mimic joint's carried by its joint), zero if none."""
    return model.friction or JointFriction(np.zeros(model.n), np.zeros(model.n), model.smoothing_velocity)


def _refuse_static(model, pg, dyn, limits, tr) -> None:
    """A pose on the path that cannot be held, or left (Coulomb), within a torque limit."""
    coulomb = _friction(model).coulomb
    moves = (np.abs(pg.q1) > 0).any(axis=0)
    need = np.abs(dyn.c) + coulomb * moves
    over = need - limits.torque
    i, j = np.unravel_index(np.argmax(over), over.shape)
    if over[i, j] > 0:
        where = f"at point {pg.point[i]}" if pg.knot[i] else f"between points {pg.point[i]} and {pg.point[i] + 1}"
        raise TrajectoryError(
            f"infeasible path: {model.joint_names[j]} needs {need[i, j]:.4g} N m to hold the pose {where} "
            f"(input t = {tr.t[0] + pg.sigma[i]:.4g} s), over its torque limit {limits.torque[j]:.4g} N m "
            f"({limits.torque_source[j]}) by {over[i, j]:.4g} N m"
        )


def _static_share(model, pg, dyn, limits) -> np.ndarray:
    """The least factor on the limits at each grid point that still holds its pose."""
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.nan_to_num(np.abs(dyn.c) / limits.torque, nan=0.0).max(axis=1)
    return np.minimum(1.0, share * 1.001)


def _rows(model, pg, dyn, limits, factor, x0, X, floor):
    """alpha, beta, gamma (G+1, R) of every limit at every grid point: u over the step ahead
    (a point's left side, where the path's q'' jumps, is left to the verification)."""
    L = limits.torque[None, :] * np.maximum(factor, floor)[:, None]  # torque: never below holding the pose
    A = limits.acceleration[None, :] * factor[:, None]
    viscous = _friction(model).viscous
    coulomb = _friction(model).coulomb
    q1, q2, a, b, c = pg.q1[1], pg.q2[1], dyn.a, dyn.b, dyn.c
    sign, d = np.sign(q1), viscous * np.abs(q1)
    root0 = np.sqrt(np.maximum(x0, 1e-12))[:, None]
    t_slope, t_icpt = d / (2 * root0), d * root0 / 2  # viscous: the tangent at x0, above
    ch_slope = d / np.sqrt(np.maximum(X, 1e-300))[:, None]  # and the chord over [0, X], below
    near = np.stack([sign, np.r_[sign[:1], sign[:-1]], np.r_[sign[1:], sign[-1:]]])  # where q'_j flips, Coulomb
    hi_slope = np.where(sign > 0, t_slope, -ch_slope * (sign < 0))
    hi_icpt = np.where(sign > 0, t_icpt, 0.0) + coulomb * (near.max(axis=0) > 0)
    lo_slope = np.where(sign < 0, -t_slope, ch_slope * (sign > 0))
    lo_icpt = np.where(sign < 0, -t_icpt, 0.0) - coulomb * (near.min(axis=0) < 0)
    torque, acceleration = np.isfinite(L), np.isfinite(A)
    rows = [
        (a * torque, (b + hi_slope) * torque, np.where(torque, L - c - hi_icpt, 0.0)),
        (-a * torque, (-b - lo_slope) * torque, np.where(torque, L + c + lo_icpt, 0.0)),
        (q1 * acceleration, q2 * acceleration, np.where(acceleration, A, 0.0)),
        (-q1 * acceleration, -q2 * acceleration, np.where(acceleration, A, 0.0)),
    ]
    return tuple(np.concatenate([r[k] for r in rows], axis=1) for k in range(3))


def _profile(model, pg, dyn, limits, factor, x0, floor, warm=None, changed=None):
    """x, u on the grid with the limits times ``factor``; the viscous friction's tangent at x0."""
    V = limits.velocity[None, :] * factor[:, None]
    speed = np.abs(pg.q1[1])
    with np.errstate(divide="ignore"):
        X = np.where(speed > 0, (V / np.where(speed > 0, speed, 1.0)) ** 2, np.inf).min(axis=1)
    if model.friction is not None and not np.isfinite(X).all():  # the chord needs an end: the curve without it
        free = _rows(model, pg, dyn, limits, factor, np.ones(len(X)), np.full(len(X), np.inf), floor)
        X = np.where(np.isfinite(X), X, 4.0 * max_velocity_curve(*free, np.minimum(X, 1e12)))
    X = np.minimum(X, 1e12)
    x0 = X if x0 is None else x0
    rows = _rows(model, pg, dyn, limits, factor, np.minimum(x0, X), X, floor)
    return topp(*rows, X, pg.delta, pg.stops, warm, changed)


def _output(pg: PathGrid, x, u, tr: Trajectory, accelerations: bool = False) -> tuple[Trajectory, np.ndarray]:
    """A point per grid point: time, position, qd = q' sd and, if asked, qdd = q' u + q'' x
    (u the mean of the steps either side; 0 at a stop inside the path)."""
    sd = np.sqrt(x)
    with np.errstate(divide="ignore"):
        dt = 2.0 * pg.delta / (sd[:-1] + sd[1:])
    if not np.isfinite(dt).all():
        i = int(np.flatnonzero(~np.isfinite(dt))[0])
        raise TrajectoryError(
            f"infeasible path: no limit lets it move on from point {pg.point[i]} "
            f"(input t = {tr.t[0] + pg.sigma[i]:.4g} s)"
        )
    t = np.r_[0.0, np.cumsum(dt)]
    q1 = pg.q1[1]
    qd = q1 * sd[:, None]
    qd[pg.stops] = 0.0
    if not accelerations:
        return Trajectory.of(tr.joint_names, t, pg.q, qd), t
    ubar = np.r_[u[0], (u[:-1] + u[1:]) / 2, u[-1]]
    qdd = pg.q2.mean(axis=0) * x[:, None] + q1 * ubar[:, None]
    inside = pg.stops.copy()
    inside[[0, -1]] = False
    qdd[inside] = 0.0
    return Trajectory.of(tr.joint_names, t, pg.q, qd, qdd), t


def _ratios(model, out: Trajectory, limits: Limits, verify: int, segments=None) -> np.ndarray:
    """The largest value / limit per output interval (of those in ``segments``; 0 for the
    others) on ``verify`` samples each."""
    sp = spline(out)
    t, seg = sample_times(sp, verify, segments=segments)
    out_r = np.zeros(len(sp.T))
    if len(t) == 0:
        return out_r
    values = profiles(model, sp, t, seg)
    r = np.zeros(len(t))
    for name in ("torque", "velocity", "acceleration"):
        inverse = 1.0 / getattr(limits, name)  # 0 where there is no limit
        r = np.maximum(r, (np.abs(values[name]) * inverse).max(axis=1))
    out_r[seg[:: verify + 1]] = r.reshape(-1, verify + 1).max(axis=1)  # verify + 1 samples a segment
    return out_r


def _changed(x, previous) -> np.ndarray | None:
    """The output intervals whose playback may differ from the previous round's: those with
    a point within REACH of a grid point whose x changed (None: all)."""
    if previous is None:
        return None
    moved = np.convolve((x != previous).astype(float), np.ones(2 * REACH + 1), mode="same") > 0
    return np.flatnonzero(moved[:-1] | moved[1:])
