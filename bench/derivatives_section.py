"""bench_core's section on the derivatives of the dynamics: ``rnea_derivatives``,
``forward_dynamics_derivatives`` and ``inverse_mass_matrix`` (native, ready by ``prepare``)
against Pinocchio's ``computeRNEADerivatives``, ``computeABADerivatives`` and
``computeMinverse`` from Python, per call, in alternating blocks, on the same arms.

Pinocchio has no joint friction: before timing, each pair is checked to agree (1e-9 of
the largest entry) with the friction's own derivatives added to Pinocchio's side and its
forward dynamics run at tau - tau_f(qd)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from common import Figure, Row, Target  # first: puts the checkout on sys.path

from irb140_dynamics.core import (
    DERIVATIVE_KERNELS,
    forward_dynamics_derivatives,
    inverse_mass_matrix,
    prepare,
    rnea_derivatives,
)

TARGET = 0.5  # ours / Pinocchio's per call, native, each arm and function
RTOL = 1e-9


def derivative_rows(arms: dict, paired, seed: int) -> list[Row]:
    """``arms``: name -> (our model, Pinocchio's); ``paired(ours, baseline)`` -> the two
    lists of seconds per call (alternating blocks)."""
    rows = []
    for name, (model, pm) in arms.items():
        data = pm.createData()
        if not prepare(model, timeout=600.0, names=DERIVATIVE_KERNELS).native:
            print(f"note: {name}: no native derivative kernels (no C compiler?): the Python forms are timed")
        rng = np.random.default_rng(seed)
        lower, upper = np.array([j.position_limits for j in model.joints]).T
        q, qd, qdd = rng.uniform(lower, upper), rng.uniform(-2.0, 2.0, model.n), rng.uniform(-5.0, 5.0, model.n)
        tau = rng.uniform(-20.0, 20.0, model.n)
        _check(model, pm, data, q, qd, qdd, tau, name)
        cases = [
            (
                "rnea_derivatives vs computeRNEADerivatives",
                lambda m=model: rnea_derivatives(m, q, qd, qdd),
                lambda p=pm, d=data: pin.computeRNEADerivatives(p, d, q, qd, qdd),
            ),
            (
                "forward_dynamics_derivatives vs computeABADerivatives",
                lambda m=model: forward_dynamics_derivatives(m, q, qd, tau),
                lambda p=pm, d=data: pin.computeABADerivatives(p, d, q, qd, tau),
            ),
            (
                "inverse_mass_matrix vs computeMinverse",
                lambda m=model: inverse_mass_matrix(m, q),
                lambda p=pm, d=data: pin.computeMinverse(p, d, q),
            ),
        ]
        label = f"{name}{' (with its friction)' if model.friction is not None else ''}"
        for case, ours, baseline in cases:
            timed = paired(ours, baseline)
            rows.append(
                Row(
                    "derivatives, native, alternating blocks, per call",
                    f"{label} {case}",
                    *(Figure.cost(t) for t in timed),
                    Target(TARGET),
                )
            )
    return rows


def _check(model, pm, data, q, qd, qdd, tau, name: str) -> None:
    """Ours against Pinocchio's, the friction's derivatives added to Pinocchio's side."""
    slopes, torques = np.zeros(model.n), np.zeros(model.n)
    if model.friction is not None:
        f = model.friction
        shape = f.coulomb_shape(qd)
        torques = f.torques(qd)
        slopes = f.viscous + f.coulomb * (1.0 - shape**2) / f.smoothing_velocity
    dq, dqd, M = (np.array(x) for x in pin.computeRNEADerivatives(pm, data, q, qd, qdd))
    want = (dq, dqd + np.diag(slopes), np.triu(M) + np.triu(M, 1).T)
    A, B, Minv = (np.array(x) for x in pin.computeABADerivatives(pm, data, q, qd, tau - torques))
    Minv = np.triu(Minv) + np.triu(Minv, 1).T
    pairs = [
        *zip(rnea_derivatives(model, q, qd, qdd), want),
        *zip(forward_dynamics_derivatives(model, q, qd, tau), (A, B - Minv @ np.diag(slopes), Minv)),
        (inverse_mass_matrix(model, q), Minv),
    ]
    for ours, theirs in pairs:
        error = np.max(np.abs(ours - theirs)) / max(np.max(np.abs(theirs)), 1e-3)
        assert error <= RTOL, f"{name}: derivatives differ from Pinocchio's by {error:.1e}"
