"""Inverse and forward dynamics of a RobotModel: the public functions.

    M(q) qdd + C(q, qd) qd + g(q) + tau_f(qd) = tau      (+ the flange wrench, see ``rnea``)

M includes the joints' armature (rotor inertia); tau_f is joint friction (see ``friction``).

Single-state functions take sequences of n numbers and return NumPy arrays; the
``*_batch`` forms take arrays shaped (N, n) and give the same numbers for N states at once.
All run the model's generated kernels (``codegen.kernels.kernels_of``), traced on first
use; ``rnea``, ``gravity``, ``mass_matrix`` and the batch forms run them as C once
compiled (by the ``native`` room), the same numbers bit for bit: in the background after
PROMOTE_AFTER calls (a batch counting once), or at once with ``prepare(model, timeout)``.
What a state is, and the checks of each argument, are in ``states``: anything else raises
ValueError naming the argument (the kernels fold constants: a NaN times a zero constant
would vanish). A result is never silently
non-finite: where velocities, accelerations, torques or a wrench are so large that it
overflows, ValueError says so, naming the inputs. g(q) and M(q) need no such check: q
enters through cos and sin only, and the model's sanity caps keep them finite.
"""

from __future__ import annotations

from collections.abc import Sequence
from math import isfinite

import numpy as np

from irb140_dynamics.core.codegen.kernels import VERBS_KERNELS, Preparation, kernels_of, prepare

__all__ = [  # prepare, Preparation: make a model's kernels native now (see codegen.kernels)
    "Preparation",
    "coriolis",
    "coriolis_batch",
    "coriolis_matrix",
    "forward_dynamics",
    "forward_dynamics_batch",
    "gravity",
    "gravity_batch",
    "mass_matrix",
    "mass_matrix_batch",
    "prepare",
    "rnea",
    "rnea_batch",
]
from irb140_dynamics.core.codegen.layout import upper_to_full
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.model.states import finite_result, finite_results, state, states

ArrayLike = Sequence[float] | np.ndarray
_ARRAY, _FLOAT64 = np.ndarray, np.dtype(float)
_KEPT = VERBS_KERNELS.kept  # id(model) -> its kernels: read inline on the hot paths, else kernels_of


def rnea(model: RobotModel, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, f_ext=None) -> np.ndarray:
    """Joint torques tau(q, qd, qdd) [N m] by recursive Newton-Euler: gravity, payload,
    armature and friction included.

    ``f_ext`` (optional, 6 numbers): the wrench (force [N], moment [N m] about the flange
    origin) that the environment exerts on the flange, in the flange frame. tau balances
    it: tau = ID(q, qd, qdd) - J(q)^T f_ext, with J the flange Jacobian in the flange frame.
    """
    kernels = _KEPT.get(id(model)) or kernels_of(model)
    if f_ext is None:
        kernel = kernels.rnea_with_friction
        if kernel.native is not None:  # checks the arrays itself: None unless (n,) float64, finite
            tau = kernel.native(q, qd, qdd)
            if tau is not None:
                return tau
        kernel.used()
    shape = kernels.shape
    if (  # the common case checked at once, inline: rnea is the hot path
        type(q) is _ARRAY
        and type(qd) is _ARRAY
        and type(qdd) is _ARRAY
        and q.dtype is _FLOAT64
        and qd.dtype is _FLOAT64
        and qdd.dtype is _FLOAT64
        and q.shape == shape
        and qd.shape == shape
        and qdd.shape == shape
    ):
        args = q.tolist(), qd.tolist(), qdd.tolist()
        if not isfinite(sum(args[2], sum(args[1], sum(args[0])))):  # a finite sum: all finite
            args = (state(q, kernels.n, "q"), state(qd, kernels.n, "qd"), state(qdd, kernels.n, "qdd"))
    else:
        args = (state(q, kernels.n, "q"), state(qd, kernels.n, "qd"), state(qdd, kernels.n, "qdd"))
    if f_ext is None:  # friction inside
        tau = kernels.rnea_with_friction.scalar(*args)
    else:
        tau = kernels.rnea_wrench.scalar(*args, state(f_ext, 6, "f_ext"))
        if model.friction is not None:
            tau = model.friction.added(tau, args[1])
    if not isfinite(sum(tau)):  # inline: rnea is the hot path
        finite_result(tau, "rnea", q=q, qd=qd, qdd=qdd, **({} if f_ext is None else {"f_ext": f_ext}))
    return np.array(tau)


def gravity(model: RobotModel, q: ArrayLike) -> np.ndarray:
    """Gravity torques g(q) [N m]: what holds the arm (and payload) still at q."""
    kernels = _KEPT.get(id(model)) or kernels_of(model)
    kernel = kernels.gravity_torques
    if kernel.native is not None:
        g = kernel.native(q)
        if g is not None:
            return g
    kernel.used()
    if type(q) is _ARRAY and q.dtype is _FLOAT64 and q.shape == kernels.shape:  # the common case, inline
        q_list = q.tolist()
        if not isfinite(sum(q_list)):
            q_list = state(q, kernels.n, "q")
    else:
        q_list = state(q, kernels.n, "q")
    return np.array(kernel.scalar(q_list))


def coriolis(model: RobotModel, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
    """Coriolis and centrifugal torques C(q, qd) qd [N m]."""
    c = kernels_of(model).coriolis.scalar(state(q, model.n, "q"), state(qd, model.n, "qd"))
    return np.array(finite_result(c, "coriolis", q=q, qd=qd))


def coriolis_matrix(model: RobotModel, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
    """The Coriolis matrix C(q, qd) of the Christoffel symbols: Mdot - 2C is skew-symmetric."""
    n = model.n
    flat = kernels_of(model).coriolis_matrix.scalar(state(q, n, "q"), state(qd, n, "qd"))
    return np.array(finite_result(flat, "coriolis_matrix", q=q, qd=qd)).reshape(n, n)


def mass_matrix(model: RobotModel, q: ArrayLike) -> np.ndarray:
    """The joint-space mass matrix M(q) [kg m^2], symmetric positive definite."""
    kernel = (_KEPT.get(id(model)) or kernels_of(model)).mass_matrix
    if kernel.native is not None:
        M = kernel.native(q)  # the whole matrix
        if M is not None:
            return M
    kernel.used()
    n = model.n
    upper = kernel.scalar(state(q, n, "q"))
    return np.fromiter(upper, float, len(upper))[upper_to_full(n)]


def forward_dynamics(model: RobotModel, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, f_ext=None) -> np.ndarray:
    """Joint accelerations qdd = M(q)^-1 (tau - C(q, qd) qd - g(q) - tau_f(qd)) [rad/s^2]."""
    n, kernels = model.n, kernels_of(model)
    args = (state(q, n, "q"), state(qd, n, "qd"), [0.0] * n)
    tau_in = state(tau, n, "tau")
    if f_ext is None:
        bias = np.array(kernels.rnea.scalar(*args))
    else:
        bias = np.array(kernels.rnea_wrench.scalar(*args, state(f_ext, 6, "f_ext")))
    if model.friction is not None:
        bias += model.friction.torques(args[1])
    M = _symmetric(np.array(kernels.mass_matrix.scalar(args[0])), n)
    with np.errstate(invalid="ignore", over="ignore"):
        try:
            qdd = np.linalg.solve(M, np.array(tau_in, dtype=float) - bias)
        except np.linalg.LinAlgError:
            raise ValueError(
                f"forward_dynamics: the mass matrix is singular at q={list(args[0])}: no inverse"
            ) from None
    finite_result(qdd.tolist(), "forward_dynamics", q=q, qd=qd, tau=tau, **({} if f_ext is None else {"f_ext": f_ext}))
    return qdd


# -- many states at once --------------------------------------------------------------


def rnea_batch(model: RobotModel, Q, QD, QDD) -> np.ndarray:
    """rnea for N states: Q, QD, QDD shaped (N, n) -> tau shaped (N, n)."""
    columns = states(model.n, Q=Q, QD=QD, QDD=QDD)
    tau = _with_friction(model, _run(kernels_of(model).rnea, *columns), columns[1])
    return finite_results(tau, "rnea_batch", "Q", "QD", "QDD")


def gravity_batch(model: RobotModel, Q) -> np.ndarray:
    """gravity for N states: Q shaped (N, n) -> g shaped (N, n)."""
    return _run(kernels_of(model).gravity_torques, *states(model.n, Q=Q))


def coriolis_batch(model: RobotModel, Q, QD) -> np.ndarray:
    """coriolis for N states: (N, n) -> C(q, qd) qd shaped (N, n)."""
    return finite_results(_run(kernels_of(model).coriolis, *states(model.n, Q=Q, QD=QD)), "coriolis_batch", "Q", "QD")


def mass_matrix_batch(model: RobotModel, Q) -> np.ndarray:
    """mass_matrix for N states: Q shaped (N, n) -> M shaped (N, n, n)."""
    return _run(kernels_of(model).mass_matrix, *states(model.n, Q=Q))


def forward_dynamics_batch(model: RobotModel, Q, QD, TAU) -> np.ndarray:
    """forward_dynamics for N states: (N, n) arrays -> QDD shaped (N, n)."""
    q, qd, tau = states(model.n, Q=Q, QD=QD, TAU=TAU)
    kernels = kernels_of(model)
    bias = _with_friction(model, _run(kernels.rnea, q, qd, np.zeros_like(q)), qd)
    M = _run(kernels.mass_matrix, q)
    with np.errstate(over="ignore", invalid="ignore"):
        try:
            QDD = np.linalg.solve(M, (tau.T - bias)[..., None])[..., 0]
        except np.linalg.LinAlgError:
            raise ValueError("forward_dynamics_batch: the mass matrix is singular at a state: no inverse") from None
    return finite_results(QDD, "forward_dynamics_batch", "Q", "QD", "TAU")


def _with_friction(model: RobotModel, tau: np.ndarray, qd_columns: np.ndarray) -> np.ndarray:
    """tau (N, n) plus the friction at velocities given as (n, N) columns."""
    if model.friction is not None:
        tau += model.friction.torques(qd_columns.T)
    return tau


# -- conversions ----------------------------------------------------------------------


_CHUNK = 8192  # states per pass: the kernels' intermediates then stay in the CPU caches


def _run(kernel, *columns: np.ndarray) -> np.ndarray:
    """``kernel`` over states given as (n, N) columns: (N, outputs), whole (N, n, n)
    matrices for a kernel of M. Its native form answers when it has one (the same bits as
    the NumPy form); else, or where that declines (a result not finite), the NumPy form,
    the call counted toward making the kernel native."""
    if kernel.native_batch is not None:
        result = kernel.native_batch(*columns)
        if result is not None:
            return result
    kernel.used()
    result = _evaluate(kernel.array, *columns)
    return _symmetric(result, kernel.full_matrix) if kernel.full_matrix else result


def _evaluate(kernel, *columns: np.ndarray) -> np.ndarray:
    """An array kernel over states given as (n, N) columns, chunk by chunk: (N, outputs)."""
    N = columns[0].shape[1]
    result = None
    for start in range(0, max(N, 1), _CHUNK):
        chunk = slice(start, start + _CHUNK)
        with np.errstate(over="ignore", invalid="ignore"):  # the callers check what they return
            outputs = kernel(*(c[:, chunk] for c in columns))
        if result is None:
            result = np.empty((N, len(outputs)))
        for i, values in enumerate(outputs):  # constants folded at generation broadcast
            result[chunk, i] = values
    return result


def _symmetric(upper: np.ndarray, n: int) -> np.ndarray:
    """Symmetric (..., n, n) matrices from their upper triangles stored row by row."""
    return upper[..., upper_to_full(n)]
