"""Derivatives of the dynamics and the inverse mass matrix: the public functions.

For the equations of motion (see ``dynamics``)

    tau = ID(q, qd, qdd) = M(q) qdd + C(q, qd) qd + g(q) + tau_f(qd)
    qdd = FD(q, qd, tau) = M(q)^-1 (tau - C(q, qd) qd - g(q) - tau_f(qd))

``rnea_derivatives`` gives d ID / dq, d ID / dqd and M (= d ID / d qdd), and
``forward_dynamics_derivatives`` d FD / dq, d FD / dqd and M^-1 (= d FD / d tau): what a
linearised model x' = A x + B u needs (model-predictive control, trajectory optimisation).
Armature and friction are included, as in ``rnea``. A matrix's element [i, j] is the
derivative of output i by input j; units follow (N m / rad, N m s / rad, kg m^2, ...; for
a prismatic joint m and N).

They are exact, not finite differences: the closed forms of Carpentier and Mansard
(``algorithms.analytical_derivatives``, tested against the recursions run on dual numbers),
traced into kernels like the other functions', compiled as C after kernels.PROMOTE_AFTER
calls or at once with ``prepare(model, names=DERIVATIVE_KERNELS)``.
A state is checked as in ``dynamics``; a result that is not finite raises ValueError.
"""

from __future__ import annotations

import numpy as np

from irb140_dynamics.core.algorithms.linear import SingularMatrix
from irb140_dynamics.core.codegen.kernels import VERBS_KERNELS, kernels_of
from irb140_dynamics.core.codegen.layout import upper_to_full
from irb140_dynamics.core.model.states import finite_result, state

__all__ = ["DERIVATIVE_KERNELS", "forward_dynamics_derivatives", "inverse_mass_matrix", "rnea_derivatives"]

# the kernels these functions run, to ``prepare`` them
DERIVATIVE_KERNELS = ("rnea_derivatives", "forward_dynamics_derivatives", "inverse_mass_matrix")
_KEPT = VERBS_KERNELS.kept  # id(model) -> its kernels: read inline on the hot paths, else kernels_of


def rnea_derivatives(model, q, qd, qdd) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(d tau / dq, d tau / dqd, M), each (n, n), of ``rnea`` at (q, qd, qdd)."""
    kernel = (_KEPT.get(id(model)) or kernels_of(model)).rnea_derivatives
    native = kernel.native
    if native is not None:  # checks the arrays itself: None unless (n,) float64, finite
        out = native(q, qd, qdd)
        if type(out) is tuple:
            return out
    return _three(model, kernel, "rnea_derivatives", q=q, qd=qd, qdd=qdd)


def forward_dynamics_derivatives(model, q, qd, tau) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(d qdd / dq, d qdd / dqd, M^-1), each (n, n), of ``forward_dynamics`` at (q, qd, tau)."""
    try:
        kernel = (_KEPT.get(id(model)) or kernels_of(model)).forward_dynamics_derivatives
    except SingularMatrix as singular:
        raise _refused(model, "forward_dynamics_derivatives", singular) from None
    native = kernel.native
    if native is not None:
        out = native(q, qd, tau)
        if type(out) is tuple:
            return out
    return _three(model, kernel, "forward_dynamics_derivatives", q=q, qd=qd, tau=tau)


def inverse_mass_matrix(model, q) -> np.ndarray:
    """M(q)^-1 (n, n), symmetric positive definite (armature included)."""
    try:
        kernel = (_KEPT.get(id(model)) or kernels_of(model)).inverse_mass_matrix
    except SingularMatrix as singular:
        raise _refused(model, "inverse_mass_matrix", singular) from None
    native = kernel.native
    if native is not None:
        Minv = native(q)  # the whole matrix
        if Minv is not None:
            return Minv
    kernel.used()
    n = model.n
    upper = finite_result(_run(kernel, "inverse_mass_matrix", state(q, n, "q")), "inverse_mass_matrix", q=q)
    return np.fromiter(upper, float, len(upper))[upper_to_full(n)]


def _three(model, kernel, name: str, **inputs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The three n x n matrices of ``kernel`` (named ``name``) at the named inputs, where
    its native form gave no tuple: one array (loaded through ctypes), or None (the Python
    form then answers, or says what is wrong)."""
    n = model.n
    if kernel.native is not None:
        out = kernel.native(*inputs.values())
        if out is not None:
            first, second, third = out.reshape(3, n, n)
            return first, second, third
    kernel.used()
    values = _run(kernel, name, *(state(x, n, key) for key, x in inputs.items()))
    first, second, third = np.array(finite_result(values, name, **inputs)).reshape(3, n, n)
    return first, second, third


def _refused(model, name: str, singular: SingularMatrix) -> ValueError:
    """The error of a model whose M is singular for every q: which joint moves no inertia."""
    joint = model.joint_names[singular.index]
    return ValueError(f"{name}: the mass matrix is singular for every q (joint {joint!r} moves no inertia): no inverse")


def _run(kernel, name: str, *args):
    try:
        return kernel.scalar(*args)
    except ZeroDivisionError:  # M singular at this state
        raise ValueError(f"{name}: the mass matrix is singular at q={list(args[0])}: no inverse") from None
