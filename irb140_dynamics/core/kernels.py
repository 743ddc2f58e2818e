"""The algorithms of one model, compiled on first use (see codegen)."""

from __future__ import annotations

from functools import cached_property

from . import algorithms
from .codegen import compile_kernel


class Kernel:
    """One compiled algorithm: ``scalar`` on floats, ``array`` on NumPy arrays."""

    def __init__(self, name, algorithm, inputs, angles):
        self.source, self.scalar, self.array = compile_kernel(name, algorithm, inputs, angles)


class Kernels:
    """Each algorithm of a model as straight-line code; q comes first in every kernel."""

    def __init__(self, model):
        self.n = model.n
        self.model = model
        self.links = algorithms.chain(model)
        self.gravity = model.gravity
        self.angles = [link.theta_offset for link in self.links]

    def _kernel(self, name, algorithm, **inputs) -> Kernel:
        return Kernel(name, algorithm, inputs, self.angles)

    @cached_property
    def rnea(self) -> Kernel:
        """(q, qd, qdd) -> tau"""
        return self._kernel(
            "rnea",
            lambda cs, qd, qdd: algorithms.rnea(self.links, cs, qd, qdd, self.gravity),
            qd=self.n,
            qdd=self.n,
        )

    @cached_property
    def rnea_wrench(self) -> Kernel:
        """(q, qd, qdd, wrench) -> tau, wrench = (f, n) on the flange (see algorithms.rnea)"""
        return self._kernel(
            "rnea_wrench",
            lambda cs, qd, qdd, wrench: algorithms.rnea(
                self.links, cs, qd, qdd, self.gravity, *algorithms.flange_wrench(self.model, wrench[:3], wrench[3:])
            ),
            qd=self.n,
            qdd=self.n,
            wrench=6,
        )

    @cached_property
    def gravity_torques(self) -> Kernel:
        """q -> g(q)"""
        zeros = [0.0] * self.n
        return self._kernel(
            "gravity", lambda cs: algorithms.rnea(self.links, cs, zeros, zeros, self.gravity)
        )

    @cached_property
    def coriolis(self) -> Kernel:
        """(q, qd) -> C(q, qd) qd"""
        zeros = [0.0] * self.n
        return self._kernel(
            "coriolis",
            lambda cs, qd: algorithms.rnea(self.links, cs, qd, zeros, (0.0, 0.0, 0.0)),
            qd=self.n,
        )

    @cached_property
    def mass_matrix(self) -> Kernel:
        """q -> upper triangle of M(q), row by row"""

        def upper(cs):
            M = algorithms.crba(self.links, cs)
            return [M[i][j] for i in range(self.n) for j in range(i, self.n)]

        return self._kernel("mass_matrix", upper)

    @cached_property
    def coriolis_matrix(self) -> Kernel:
        """(q, qd) -> C(q, qd), row by row"""

        def flat(cs, qd):
            C = algorithms.christoffel_coriolis(self.links, cs, qd)
            return [x for row in C for x in row]

        return self._kernel("coriolis_matrix", flat, qd=self.n)

    @cached_property
    def regressor(self) -> Kernel:
        """(q, qd, qdd) -> the rigid-body regressor, n x 10n row by row (see regressor)."""
        from .regressor import rigid_body_regressor

        def flat(cs, qd, qdd):
            return [x for row in rigid_body_regressor(self.links, cs, qd, qdd, self.gravity) for x in row]

        return self._kernel("regressor", flat, qd=self.n, qdd=self.n)

    @cached_property
    def momentum(self) -> Kernel:
        """(q, qd) -> [M qd, C^T qd]: the generalized momentum and dT/dq (see observer)."""
        from .observer import energy_gradient

        zeros = [0.0] * self.n

        def terms(cs, qd):
            p = algorithms.rnea(self.links, cs, zeros, qd, (0.0, 0.0, 0.0))  # M qd
            return [*p, *energy_gradient(self.links, cs, qd)]

        return self._kernel("momentum", terms, qd=self.n)
