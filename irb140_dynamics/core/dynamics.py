"""Inverse and forward dynamics of a RobotModel: the public functions.

    M(q) qdd + C(q, qd) qd + g(q) + tau_f(qd) = tau      (+ the flange wrench, see ``rnea``)

M includes the joints' armature (rotor inertia); tau_f is joint friction (see ``friction``).

Single-state functions take sequences of n numbers and return NumPy arrays; the
``*_batch`` forms take arrays shaped (N, n) and give the same numbers for N states at once.
All run the model's generated kernels (see ``codegen``), compiled on first use. A value
that is not finite, a wrong length, or batch arguments of different N raise ValueError
naming the argument (the kernels fold constants: a NaN times a zero constant would vanish).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Sequence

import numpy as np

from .model import RobotModel

ArrayLike = Sequence[float] | np.ndarray


def rnea(model: RobotModel, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, f_ext=None) -> np.ndarray:
    """Joint torques tau(q, qd, qdd) [N m] by recursive Newton-Euler: gravity, payload,
    armature and friction included.

    ``f_ext`` (optional, 6 numbers): the wrench (force [N], moment [N m] about the flange
    origin) that the environment exerts on the flange, in the flange frame. tau balances
    it: tau = ID(q, qd, qdd) - J(q)^T f_ext, with J the flange Jacobian in the flange frame.
    """
    kernels = model.kernels
    args = (_state(q, model.n, "q"), _state(qd, model.n, "qd"), _state(qdd, model.n, "qdd"))
    if f_ext is None:
        tau = np.array(kernels.rnea.scalar(*args))
    else:
        tau = np.array(kernels.rnea_wrench.scalar(*args, _state(f_ext, 6, "f_ext")))
    if model.friction is not None:
        tau += model.friction.torques(args[1])
    return tau


def gravity(model: RobotModel, q: ArrayLike) -> np.ndarray:
    """Gravity torques g(q) [N m]: what holds the arm (and payload) still at q."""
    return np.array(model.kernels.gravity_torques.scalar(_state(q, model.n, "q")))


def coriolis(model: RobotModel, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
    """Coriolis and centrifugal torques C(q, qd) qd [N m]."""
    return np.array(model.kernels.coriolis.scalar(_state(q, model.n, "q"), _state(qd, model.n, "qd")))


def coriolis_matrix(model: RobotModel, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
    """The Coriolis matrix C(q, qd) of the Christoffel symbols: Mdot - 2C is skew-symmetric."""
    n = model.n
    flat = model.kernels.coriolis_matrix.scalar(_state(q, n, "q"), _state(qd, n, "qd"))
    return np.array(flat).reshape(n, n)


def mass_matrix(model: RobotModel, q: ArrayLike) -> np.ndarray:
    """The joint-space mass matrix M(q) [kg m^2], symmetric positive definite."""
    n = model.n
    return _symmetric(np.array(model.kernels.mass_matrix.scalar(_state(q, n, "q"))), n)


def forward_dynamics(model: RobotModel, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, f_ext=None) -> np.ndarray:
    """Joint accelerations qdd = M(q)^-1 (tau - C(q, qd) qd - g(q) - tau_f(qd)) [rad/s^2]."""
    tau = np.array(_state(tau, model.n, "tau"), dtype=float)
    bias = rnea(model, q, qd, np.zeros(model.n), f_ext)
    return np.linalg.solve(mass_matrix(model, q), tau - bias)


# -- many states at once --------------------------------------------------------------


def rnea_batch(model: RobotModel, Q, QD, QDD) -> np.ndarray:
    """rnea for N states: Q, QD, QDD shaped (N, n) -> tau shaped (N, n)."""
    columns = _columns(model.n, Q=Q, QD=QD, QDD=QDD)
    return _with_friction(model, _evaluate(model.kernels.rnea.array, *columns), columns[1])


def gravity_batch(model: RobotModel, Q) -> np.ndarray:
    """gravity for N states: Q shaped (N, n) -> g shaped (N, n)."""
    return _evaluate(model.kernels.gravity_torques.array, *_columns(model.n, Q=Q))


def coriolis_batch(model: RobotModel, Q, QD) -> np.ndarray:
    """coriolis for N states: (N, n) -> C(q, qd) qd shaped (N, n)."""
    return _evaluate(model.kernels.coriolis.array, *_columns(model.n, Q=Q, QD=QD))


def mass_matrix_batch(model: RobotModel, Q) -> np.ndarray:
    """mass_matrix for N states: Q shaped (N, n) -> M shaped (N, n, n)."""
    return _symmetric(_evaluate(model.kernels.mass_matrix.array, *_columns(model.n, Q=Q)), model.n)


def forward_dynamics_batch(model: RobotModel, Q, QD, TAU) -> np.ndarray:
    """forward_dynamics for N states: (N, n) arrays -> QDD shaped (N, n)."""
    q, qd, tau = _columns(model.n, Q=Q, QD=QD, TAU=TAU)
    bias = _with_friction(model, _evaluate(model.kernels.rnea.array, q, qd, np.zeros_like(q)), qd)
    M = _symmetric(_evaluate(model.kernels.mass_matrix.array, q), model.n)
    return np.linalg.solve(M, (tau.T - bias)[..., None])[..., 0]


def _with_friction(model: RobotModel, tau: np.ndarray, qd_columns: np.ndarray) -> np.ndarray:
    """tau (N, n) plus the friction at velocities given as (n, N) columns."""
    if model.friction is not None:
        tau += model.friction.torques(qd_columns.T)
    return tau


# -- conversions ----------------------------------------------------------------------


def _state(x, n: int, name: str):
    """A sequence of n finite numbers as the kernels want it: a list of Python floats."""
    if isinstance(x, np.ndarray):
        if x.shape != (n,):
            raise ValueError(f"{name}: expected shape ({n},), got {x.shape}")
        x = x.tolist()
    elif len(x) != n:
        raise ValueError(f"{name}: expected {n} values, got {len(x)}")
    # a finite sum is all finite (nan and inf carry through a sum); it only costs ~0.1 us
    if not math.isfinite(sum(x)) and not all(map(math.isfinite, x)):
        raise ValueError(f"{name}: must be finite, got {list(x)}")
    return x


def _columns(n: int, **arrays) -> list[np.ndarray]:
    """Arrays of N states (N, n), given by name, as the kernels want them: (n, N) columns,
    finite, all of the first one's N."""
    columns = []
    for name, X in arrays.items():
        X = np.asarray(X, dtype=float)
        if X.ndim != 2 or X.shape[1] != n:
            raise ValueError(f"{name}: expected shape (N, {n}), got {X.shape}")
        if columns and X.shape[0] != columns[0].shape[1]:
            first = next(iter(arrays))
            raise ValueError(f"{name}: expected {columns[0].shape[1]} states like {first}, got {X.shape[0]}")
        if not np.isfinite(X).all():
            raise ValueError(f"{name}: must be finite (state {int(np.argmin(np.isfinite(X).all(axis=1)))} is not)")
        columns.append(np.ascontiguousarray(X.T))
    return columns


_CHUNK = 8192  # states per pass: the kernels' intermediates then stay in the CPU caches


def _evaluate(kernel, *columns: np.ndarray) -> np.ndarray:
    """An array kernel over states given as (n, N) columns, chunk by chunk: (N, outputs)."""
    N = columns[0].shape[1]
    result = None
    for start in range(0, max(N, 1), _CHUNK):
        chunk = slice(start, start + _CHUNK)
        outputs = kernel(*(c[:, chunk] for c in columns))
        if result is None:
            result = np.empty((N, len(outputs)))
        for i, values in enumerate(outputs):  # constants folded at generation broadcast
            result[chunk, i] = values
    return result


def _symmetric(upper: np.ndarray, n: int) -> np.ndarray:
    """Symmetric (..., n, n) matrices from their upper triangles stored row by row."""
    return upper[..., _upper_to_full(n)]


@lru_cache(maxsize=None)
def _upper_to_full(n: int) -> np.ndarray:
    """For each entry of an n x n matrix, its index in the row-by-row upper triangle."""
    index = np.empty((n, n), dtype=np.intp)
    rows, cols = np.triu_indices(n)
    index[rows, cols] = index[cols, rows] = np.arange(len(rows))
    return index
