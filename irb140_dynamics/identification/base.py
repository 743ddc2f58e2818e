"""Base parameters: the combinations of the dynamic parameters that joint torques determine.

Joint torques are linear in the 13 n parameters pi (``core.regressor``), but not every
parameter shows in them: a link's mass on the axis of the joints before it never moves
them, two parameters may always act together (joint 1's armature and its link's Izz), or a
parameter may act only as a fixed combination of others. The torques determine only

    beta = pi[independent] + B pi[dependent]                    (r numbers, r <= 13 n)

and Y pi = Y[:, independent] beta for every state. They are found numerically (Gautier
1990): the regressor of many random states within the joints' limits is stacked, QR with
column pivoting gives its rank r, and QR in pi's order picks the leading parameter of each
combination: a column that is a combination of earlier ones (its R_ii ~ 0) is dependent,
so each base parameter is an earlier link's parameter plus later links' ones, the form of
the classical regrouping rules (Khalil & Dombre). Columns that are zero for every state
are unidentifiable: they have no effect on any torque.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import qr

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.regressor import parameter_names, regressor_batch

RANK_TOLERANCE = 1e-8  # |R_ii| of unit-norm columns below this: dependent
DEFAULT_STATES = 400


@dataclass(frozen=True, eq=False)
class BaseParameters:
    """The base parameters of a model's structure (see the module's docstring)."""

    names: tuple[str, ...]  # of pi's 13 n entries
    independent: np.ndarray  # (r,) indices into pi: each base parameter's leading parameter
    dependent: np.ndarray  # indices into pi regrouped into the base parameters
    regrouping: np.ndarray  # B (r, len(dependent)): Y[:, dependent] = Y[:, independent] B
    unidentifiable: np.ndarray  # indices into pi with no effect on any torque

    @property
    def count(self) -> int:
        return len(self.independent)

    def matrix(self) -> np.ndarray:
        """K (r, 13 n): beta = K pi."""
        K = np.zeros((self.count, len(self.names)))
        K[:, self.independent] = np.eye(self.count)
        K[:, self.dependent] = self.regrouping
        return K

    def of(self, pi) -> np.ndarray:
        """beta of a full parameter vector pi (13 n,), or of many (..., 13 n)."""
        pi = np.asarray(pi, dtype=float)
        return pi[..., self.independent] + pi[..., self.dependent] @ self.regrouping.T

    def columns(self, Y: np.ndarray) -> np.ndarray:
        """The base regressor: Y's columns of the leading parameters (Y @ pi == Y_b @ beta)."""
        return Y[..., self.independent]

    def labels(self) -> list[str]:
        """Short names: the leading parameter's name, e.g. 'joint_2.Izz'."""
        return [self.names[i] for i in self.independent]

    def describe(self, digits: int = 6) -> list[str]:
        """Each base parameter as a linear combination of named parameters."""
        lines = []
        for row, leading in enumerate(self.independent):
            terms = [self.names[leading]]
            for coefficient, column in zip(self.regrouping[row], self.dependent):
                if coefficient != 0.0:
                    terms.append(_term(coefficient, self.names[column], digits))
            lines.append(f"b{row + 1:<3d} = {' '.join([terms[0], *terms[1:]])}")
        return lines


def _term(coefficient: float, name: str, digits: int) -> str:
    sign = "-" if coefficient < 0 else "+"
    size = abs(coefficient)
    return f"{sign} {name}" if math.isclose(size, 1.0, rel_tol=1e-9) else f"{sign} {size:.{digits}g} {name}"


def random_states(model: RobotModel, count: int, rng) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Q, QD, QDD) uniform within the joints' position, velocity and acceleration limits
    (+-2 rad/s and +-10 rad/s^2 where a joint gives none)."""
    lower, upper = np.array([j.position_limits for j in model.independent_joints]).T
    speed = np.array([j.velocity_limit or 2.0 for j in model.independent_joints])
    acceleration = np.array([j.acceleration_limit or 10.0 for j in model.independent_joints])
    shape = (count, model.n)
    return (
        rng.uniform(lower, upper, shape),
        rng.uniform(-speed, speed, shape),
        rng.uniform(-acceleration, acceleration, shape),
    )


def find_base_parameters(model: RobotModel, states: int = DEFAULT_STATES, seed: int = 0) -> BaseParameters:
    """The base parameters of ``model``'s structure (kinematics, gravity direction, joints)."""
    Y = regressor_batch(model, *random_states(model, states, np.random.default_rng(seed)))
    Y = Y.reshape(-1, Y.shape[-1])
    norms = np.linalg.norm(Y, axis=0)
    scale = norms.max()
    moving = np.flatnonzero(norms > RANK_TOLERANCE * scale)
    unit = Y[:, moving] / norms[moving]
    _, R_pivoted, _ = qr(unit, mode="economic", pivoting=True)
    diagonal = np.abs(np.diag(R_pivoted))
    rank = int(np.sum(diagonal > RANK_TOLERANCE * diagonal[0]))
    _, R = qr(unit, mode="economic")
    leading = np.abs(np.diag(R)) > RANK_TOLERANCE
    if leading.sum() != rank:
        raise ArithmeticError(f"base parameters: rank {rank} but {leading.sum()} leading columns; try more states")
    independent, dependent = moving[leading], moving[~leading]
    regrouping = np.linalg.lstsq(Y[:, independent], Y[:, dependent], rcond=None)[0]
    regrouping[np.abs(regrouping) < 1e-10 * max(1.0, np.abs(regrouping).max(initial=0.0))] = 0.0
    unidentifiable = np.setdiff1d(np.arange(Y.shape[1]), moving)
    return BaseParameters(tuple(parameter_names(model)), independent, dependent, regrouping, unidentifiable)
