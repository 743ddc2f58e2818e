"""toppra (Pham and Pham's TOPP-RA library) on the same path, grid and limits as our
``retime``: the baseline of the time-optimality tests and of bench/bench_retime.py.

The path is our PathGrid (the controller's interpolation of the input, by path length);
toppra gets it through a geometric-path object that answers at the grid points. Torque
through toppra's JointTorqueConstraint with our rnea (Coulomb friction as its fs_coef;
viscous friction it cannot take: compare on models without it). toppra's profile is played
like ours (a point per grid point, the controller's cubic interpolation) and, as toppra only
constrains grid points, its limits are lowered until the playback sampled 10x finer is
within every limit ("at 0 violations").
"""

from __future__ import annotations

import numpy as np
import toppra
import toppra.algorithm as algo
from toppra import constraint

from irb140_dynamics.core.dynamics import rnea
from irb140_dynamics.core.trajectories import retiming as retime_module
from irb140_dynamics.core.trajectories.path import PathGrid

toppra.setup_logging("WARNING")
FINITE = 1e9  # stands for "no limit": toppra wants numbers


class GridPath(toppra.interpolator.AbstractGeometricPath):
    """The path at its grid points only (toppra evaluates it nowhere else with a given grid)."""

    def __init__(self, pg: PathGrid):
        self.pg = pg

    def __call__(self, s, order=0):
        s = np.atleast_1d(s)
        i = np.clip(np.searchsorted(self.pg.s, s), 0, len(self.pg.s) - 1)
        if not np.allclose(self.pg.s[i], s, rtol=0, atol=1e-12):
            raise ValueError("GridPath: evaluated off the grid")
        return (self.pg.q, self.pg.q1[1], self.pg.q2[1])[order][i]

    @property
    def dof(self):
        return self.pg.q.shape[1]

    @property
    def path_interval(self):
        return np.array([self.pg.s[0], self.pg.s[-1]])


def toppra_x(model, pg: PathGrid, limits, factor: float = 1.0) -> np.ndarray:
    """toppra's x = sd^2 at the grid points (rest to rest), limits times ``factor``."""

    def finite(v):
        return np.where(np.isfinite(v), v * factor, FINITE)

    v, a, tau = finite(limits.velocity), finite(limits.acceleration), finite(limits.torque)
    coulomb = np.array([j.friction.coulomb for j in model.joints])
    zero = np.zeros(model.n)

    def inv_dyn(q, qd, qdd):
        return rnea(model, q, qd, qdd) - (model.friction.torques(qd) if model.friction else zero)

    constraints = [
        constraint.JointVelocityConstraint(np.c_[-v, v]),
        constraint.JointAccelerationConstraint(np.c_[-a, a]),
        constraint.JointTorqueConstraint(inv_dyn, np.c_[-tau, tau], coulomb),
    ]
    instance = algo.TOPPRA(constraints, GridPath(pg), gridpoints=pg.s, solver_wrapper="seidel")
    _, sd, _, _ = instance.compute_parameterization(0, 0, return_data=True)
    if sd is None:
        raise RuntimeError("toppra: no parameterization")
    return np.maximum(sd, 0.0) ** 2


def toppra_duration(pg: PathGrid, x) -> float:
    sd = np.sqrt(x)
    return float((2.0 * np.diff(pg.s) / (sd[:-1] + sd[1:])).sum())


def toppra_within_limits(model, pg: PathGrid, tr, limits, verify: int = 10, rounds: int = 20):
    """(duration at 0 violations, raw duration, worst use of a limit of the raw output, factor)."""
    factor, raw, raw_worst = 1.0, None, None
    for _ in range(rounds):
        x = toppra_x(model, pg, limits, factor)
        u = np.diff(x) / (2.0 * np.diff(pg.s))
        out, _ = retime_module._output(pg, x, u, tr)
        worst = float(retime_module._ratios(model, out, limits, verify).max())
        if raw is None:
            raw, raw_worst = out.duration, worst
        if worst <= 1.0:
            return out.duration, raw, raw_worst, factor
        factor *= 0.999 / worst
    raise RuntimeError("toppra: still over a limit after lowering them")
