"""Every kernel by name (``RECIPES``): how each is traced from the algorithms, on an arm
whose payload's numbers and gravity come from the argument ``k`` (see kernels.ArmKernels)."""

from __future__ import annotations

from dataclasses import dataclass

from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.algorithms.derivatives import christoffel, christoffel_coriolis
from irb140_dynamics.core.algorithms.momentum import momentum_terms
from irb140_dynamics.core.algorithms.regressor import rigid_body_regressor
from irb140_dynamics.core.codegen import derivative_kernels as derivatives


@dataclass(frozen=True)
class Recipe:
    """How a kernel is traced: ``algorithm(arm, cs, *groups, k)`` -> outputs, the argument
    groups after q (each n long, ``wrench`` 6), whether its outputs are M's upper
    triangle (the C form then writes M whole), whether it takes the model's joint
    friction (``friction``: its coefficients appended to k, see ``derivative_kernels``;
    the algorithm then gets the keyword ``friction``, None, "viscous" or "coulomb"), and
    how many n x n matrices its outputs are, row by row (see ``Program.matrices``)."""

    algorithm: object
    groups: tuple[str, ...] = ()
    matrix: bool = False
    friction: bool = False
    matrices: int = 0


def _rnea(arm, cs, qd, qdd, k):
    cs, qd, qdd = arm.expanded(cs, qd, qdd)
    return arm.projected(algorithms.rnea(arm.links_with(k), cs, qd, qdd, arm.gravity_of(k)))


def _rnea_wrench(arm, cs, qd, qdd, wrench, k):
    cs, qd, qdd = arm.expanded(cs, qd, qdd)
    force, moment = algorithms.flange_wrench(arm.flange, wrench[:3], wrench[3:])
    links, gravity = arm.links_with(k), arm.gravity_of(k)
    return arm.projected(algorithms.rnea(links, cs, qd, qdd, gravity, force, moment, at=arm.carrier))


def _gravity(arm, cs, k):
    zeros = [0.0] * arm.n_links
    (cs,) = arm.expanded(cs)
    return arm.projected(algorithms.rnea(arm.links_with(k), cs, zeros, zeros, arm.gravity_of(k)))


def _coriolis(arm, cs, qd, k):
    cs, qd = arm.expanded(cs, qd)
    return arm.projected(algorithms.rnea(arm.links_with(k), cs, qd, [0.0] * arm.n_links, (0.0, 0.0, 0.0)))


def _mass_matrix(arm, cs, k):
    (cs,) = arm.expanded(cs)
    M = arm.projected_matrix(algorithms.crba(arm.links_with(k), cs))
    return [M[i][j] for i in range(arm.n) for j in range(i, arm.n)]


def _coriolis_matrix(arm, cs, qd, k):
    if arm.coupled is None:
        return [x for row in christoffel_coriolis(arm.links_with(k), cs, qd) for x in row]
    (angles,) = arm.expanded(arm.dual_angles(cs, arm.n))  # M(q) of the coordinates, on dual numbers
    M = arm.projected_matrix(algorithms.crba(arm.links_with(k), angles))
    return [x for row in christoffel(M, qd) for x in row]


def _regressor(arm, cs, qd, qdd, k):
    # column by column, as the algorithm computes them: then the array form (see
    # array_code) keeps few intermediates alive (29 buffers for the IRB-140, not 138); with
    # mimic joints each link's column is carried by the coordinates, G^T Y_all (virtual work)
    cs, qd, qdd = arm.expanded(cs, qd, qdd)
    Y = rigid_body_regressor(arm.links_with(k), cs, qd, qdd, arm.gravity_of(k))
    return [x for column in zip(*Y) for x in arm.projected(column)]


def _momentum(arm, cs, qd, k):
    cs, qd = arm.expanded(cs, qd)
    terms = momentum_terms(arm.links_with(k), cs, qd)
    return arm.projected(terms[: arm.n_links]) + arm.projected(terms[arm.n_links :])


def _monitor(arm, cs, qd, qdd, k):
    cs, qd, qdd = arm.expanded(cs, qd, qdd)
    links, gravity, zeros = arm.links_with(k), arm.gravity_of(k), [0.0] * arm.n_links
    terms = momentum_terms(links, cs, qd)
    return [
        *arm.projected(algorithms.rnea(links, cs, qd, qdd, gravity)),
        *arm.projected(algorithms.rnea(links, cs, zeros, zeros, gravity)),
        *arm.projected(terms[: arm.n_links]),
        *arm.projected(terms[arm.n_links :]),
    ]


RECIPES = {  # every kernel, by name; q comes first in each
    "rnea": Recipe(_rnea, ("qd", "qdd")),  # (q, qd, qdd) -> tau
    "rnea_wrench": Recipe(_rnea_wrench, ("qd", "qdd", "wrench")),  # + (f, n) on the flange
    "gravity_torques": Recipe(_gravity),  # q -> g(q)
    "coriolis": Recipe(_coriolis, ("qd",)),  # (q, qd) -> C(q, qd) qd
    "mass_matrix": Recipe(_mass_matrix, matrix=True),  # q -> upper triangle of M, row by row
    "coriolis_matrix": Recipe(_coriolis_matrix, ("qd",)),  # (q, qd) -> C, row by row
    "regressor": Recipe(_regressor, ("qd", "qdd")),  # n x 10n, column by column
    "momentum": Recipe(_momentum, ("qd",)),  # (q, qd) -> [M qd, C^T qd] (see observer)
    "monitor": Recipe(_monitor, ("qd", "qdd")),  # [tau, g, M qd, C^T qd], one pass
    # the derivatives (see derivative_kernels), n x n matrices row by row, friction inside
    "rnea_derivatives": Recipe(  # [dtau/dq, dtau/dqd, M]
        derivatives.rnea_derivatives, ("qd", "qdd"), friction=True, matrices=3
    ),
    "forward_dynamics_qdd": Recipe(derivatives.forward_dynamics, ("qd", "tau"), friction=True),  # (q, qd, tau) -> qdd
    "forward_dynamics_derivatives": Recipe(  # [dqdd/dq, dqdd/dqd, M^-1]
        derivatives.forward_dynamics_derivatives, ("qd", "tau"), friction=True, matrices=3
    ),
    "inverse_mass_matrix": Recipe(derivatives.inverse_mass_matrix, matrix=True),  # q -> upper triangle of M^-1
}
# rnea with the model's joint friction inside (its coefficients appended to k); the model's
# plain ``rnea`` when it has none
WITH_FRICTION = "rnea_with_friction"
