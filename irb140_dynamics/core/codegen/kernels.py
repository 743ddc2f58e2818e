"""The algorithms of one model, compiled on first use (see codegen).

The payload (merged into the last link) and gravity are not folded into the code: their
13 numbers (m, h, I about the origin of the last link; g) are the kernels' last argument
``k``, whose default is the model's own. Only the zero ones are folded (as the rest of the
model is), so models that differ only in payload or gravity share their compiled code
(cached per arm and pattern of zeros, see ``_arm``): changing the payload mass, or moving
it along the flange axis, compiles nothing; the code is as short as a fully folded one.
"""

from __future__ import annotations

import types
from dataclasses import dataclass, replace
from functools import cached_property, lru_cache

from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.algorithms.momentum import momentum_terms
from irb140_dynamics.core.algorithms.regressor import rigid_body_regressor
from irb140_dynamics.core.codegen import native
from irb140_dynamics.core.codegen.array_code import compile_into
from irb140_dynamics.core.codegen.trace import compile_kernel
from irb140_dynamics.core.model.rigid_body import ZERO3, ZERO6

ARMS_CACHED = 16  # arms whose compiled code is kept (a model change is a new arm)


class Kernel:
    """One compiled algorithm: ``scalar`` on floats, ``array`` on NumPy arrays, and ``into``
    on NumPy arrays writing the outputs into given arrays (see array_code).

    ``native`` (bound kernels): None, or the same code compiled as C, which ``used()`` asks
    for once the Python form has run native.PROMOTE_AFTER times (see native)."""

    native = None
    _calls = 0

    def __init__(self, name, algorithm, inputs, angles, constants: int, full_matrix: int = 0):
        self._recipe = (name, algorithm, {**inputs, "k": constants}, angles)
        self._unbound, self._constants, self._full_matrix = self, None, full_matrix
        self.source, self.scalar, self.array = compile_kernel(*self._recipe)

    def bound(self, constants: tuple) -> Kernel:
        """This kernel with ``k`` defaulting to ``constants`` (one model's payload and gravity)."""
        kernel = object.__new__(Kernel)
        kernel._unbound, kernel._constants = self, constants
        kernel.source = self.source
        kernel.scalar, kernel.array = (_with_default(fn, constants) for fn in (self.scalar, self.array))
        return kernel

    def used(self) -> None:
        """Count a call of the Python form; the PROMOTE_AFTER-th asks for the native one.
        Each call compares the count it wrote: with threads, a count can be written twice
        (then asked for twice, harmless) but none is skipped, so it is asked for."""
        calls = self._calls = self._calls + 1
        if calls == native.PROMOTE_AFTER and self._constants is not None and native.enabled():
            native.COMPILER.request(self)

    def native_recipe(self) -> tuple:
        """(the traced recipe, n to write M whole or 0) for native.c_source."""
        return self._unbound._recipe, self._unbound._full_matrix

    @property
    def constants(self) -> tuple:
        return self._constants

    @cached_property
    def _compiled_into(self) -> tuple:
        if self._unbound is not self:
            _, into, written = self._unbound._compiled_into
            return None, _with_default(into, self._constants), written
        return compile_into(*self._recipe, scalars=("k",))

    @property
    def into(self):
        """(out, q, ...) -> None: the outputs at the indices ``written`` into out[index]
        (arrays of N states), compiled on first use."""
        return self._compiled_into[1]

    @property
    def written(self) -> list[int]:
        """The indices of the outputs ``into`` writes: those not folded to constants."""
        return self._compiled_into[2]


def _with_default(fn, constants: tuple):
    return types.FunctionType(fn.__code__, fn.__globals__, fn.__name__, (constants,))


class Kernels:
    """Each algorithm of a model as straight-line code; q comes first in every kernel."""

    def __init__(self, model):
        self.n = model.n
        self.shape = (model.n,)  # of a state array, compared on the hot paths
        self.links = links = algorithms.chain(model)  # the whole model's, for other number types
        self.gravity = model.gravity
        last = links[-1]
        constants = (last.m, *last.h, *last.I, *model.gravity)
        # plain floats: a NumPy scalar (a URDF inertial turned by NumPy) would make every
        # operation it enters several times slower
        self.constants = tuple(float(x) for x in constants if x != 0.0)
        arm = links[:-1] + (replace(last, m=0.0, h=ZERO3, I=ZERO6),)
        self._arm = _arm(arm, model.flange, tuple(x != 0.0 for x in constants))

    @property
    def angles(self) -> list[float]:
        """The joints' angle offsets (theta_i = q_i + offset_i); None for a prismatic joint."""
        return self._arm.angles

    def compiled(self, *names: str) -> bool:
        """Whether these kernels' code exists already (shared with a model of the same arm):
        then using them compiles nothing."""
        return all(name in vars(self._arm) for name in names)

    @cached_property
    def rnea(self) -> Kernel:
        """(q, qd, qdd) -> tau"""
        return self._arm.rnea.bound(self.constants)

    @cached_property
    def rnea_wrench(self) -> Kernel:
        """(q, qd, qdd, wrench) -> tau, wrench = (f, n) on the flange (see algorithms.rnea)"""
        return self._arm.rnea_wrench.bound(self.constants)

    @cached_property
    def gravity_torques(self) -> Kernel:
        """q -> g(q)"""
        return self._arm.gravity_torques.bound(self.constants)

    @cached_property
    def coriolis(self) -> Kernel:
        """(q, qd) -> C(q, qd) qd"""
        return self._arm.coriolis.bound(self.constants)

    @cached_property
    def mass_matrix(self) -> Kernel:
        """q -> upper triangle of M(q), row by row"""
        return self._arm.mass_matrix.bound(self.constants)

    @cached_property
    def coriolis_matrix(self) -> Kernel:
        """(q, qd) -> C(q, qd), row by row"""
        return self._arm.coriolis_matrix.bound(self.constants)

    @cached_property
    def regressor(self) -> Kernel:
        """(q, qd, qdd) -> the rigid-body regressor, n x 10n column by column (see regressor)."""
        return self._arm.regressor.bound(self.constants)

    @cached_property
    def momentum(self) -> Kernel:
        """(q, qd) -> [M qd, C^T qd]: the generalized momentum and dT/dq (see observer)."""
        return self._arm.momentum.bound(self.constants)

    @cached_property
    def monitor(self) -> Kernel:
        """(q, qd, qdd) -> [tau, g, M qd, C^T qd] (rigid body), one pass sharing the kinematics."""
        return self._arm.monitor.bound(self.constants)


def kernels_of(model) -> Kernels:
    """The model's kernels, made on first use and kept with the model (models are immutable,
    so they never go stale; a changed model is a new model, with kernels of its own)."""
    try:
        return model.__dict__["_kernels"]
    except KeyError:
        kernels = model.__dict__["_kernels"] = Kernels(model)
        return kernels


@lru_cache(maxsize=ARMS_CACHED)
def _arm(links, flange, nonzero: tuple[bool, ...]) -> _ArmKernels:
    return _ArmKernels(links, flange, nonzero)


@dataclass(frozen=True)
class _Flange:
    """What algorithms.flange_wrench reads of a model."""

    flange: object


class _ArmKernels:
    """The kernels of an arm (its links, the last one's inertia left out), compiled on first
    use; the last link's inertia and gravity come from the argument ``k``, its nonzero ones
    of the 13 numbers (``nonzero``), the others are zero."""

    def __init__(self, links, flange, nonzero: tuple[bool, ...]):
        self.n = len(links)
        self.links = links
        self.flange = _Flange(flange)
        self.nonzero = nonzero
        self.angles = [None if link.prismatic else link.theta_offset for link in links]

    def _spread(self, k) -> tuple:
        """The 13 numbers from the nonzero ones in k."""
        given = iter(k)
        return tuple(next(given) if used else 0.0 for used in self.nonzero)

    def _links(self, k):
        """The links with the last one's inertia from k."""
        x = self._spread(k)
        return self.links[:-1] + (replace(self.links[-1], m=x[0], h=x[1:4], I=x[4:10]),)

    def _gravity(self, k):
        return self._spread(k)[10:13]

    def _kernel(self, name, algorithm, full_matrix: int = 0, **inputs) -> Kernel:
        return Kernel(name, algorithm, inputs, self.angles, sum(self.nonzero), full_matrix)

    @cached_property
    def rnea(self) -> Kernel:
        return self._kernel(
            "rnea",
            lambda cs, qd, qdd, k: algorithms.rnea(self._links(k), cs, qd, qdd, self._gravity(k)),
            qd=self.n,
            qdd=self.n,
        )

    @cached_property
    def rnea_wrench(self) -> Kernel:
        return self._kernel(
            "rnea_wrench",
            lambda cs, qd, qdd, wrench, k: algorithms.rnea(
                self._links(k),
                cs,
                qd,
                qdd,
                self._gravity(k),
                *algorithms.flange_wrench(self.flange, wrench[:3], wrench[3:]),
            ),
            qd=self.n,
            qdd=self.n,
            wrench=6,
        )

    @cached_property
    def gravity_torques(self) -> Kernel:
        zeros = [0.0] * self.n
        return self._kernel(
            "gravity", lambda cs, k: algorithms.rnea(self._links(k), cs, zeros, zeros, self._gravity(k))
        )

    @cached_property
    def coriolis(self) -> Kernel:
        zeros = [0.0] * self.n
        return self._kernel(
            "coriolis",
            lambda cs, qd, k: algorithms.rnea(self._links(k), cs, qd, zeros, (0.0, 0.0, 0.0)),
            qd=self.n,
        )

    @cached_property
    def mass_matrix(self) -> Kernel:
        def upper(cs, k):
            M = algorithms.crba(self._links(k), cs)
            return [M[i][j] for i in range(self.n) for j in range(i, self.n)]

        return self._kernel("mass_matrix", upper, full_matrix=self.n)

    @cached_property
    def coriolis_matrix(self) -> Kernel:
        def flat(cs, qd, k):
            C = algorithms.christoffel_coriolis(self._links(k), cs, qd)
            return [x for row in C for x in row]

        return self._kernel("coriolis_matrix", flat, qd=self.n)

    @cached_property
    def regressor(self) -> Kernel:
        def flat(cs, qd, qdd, k):  # column by column, as the algorithm computes them: then the
            # array form (see array_code) keeps few intermediates alive (29 buffers for the IRB-140
            # instead of 138 row by row)
            Y = rigid_body_regressor(self._links(k), cs, qd, qdd, self._gravity(k))
            return [x for column in zip(*Y) for x in column]

        return self._kernel("regressor", flat, qd=self.n, qdd=self.n)

    @cached_property
    def momentum(self) -> Kernel:
        return self._kernel("momentum", lambda cs, qd, k: momentum_terms(self._links(k), cs, qd), qd=self.n)

    @cached_property
    def monitor(self) -> Kernel:
        zeros = [0.0] * self.n

        def terms(cs, qd, qdd, k):
            links, gravity = self._links(k), self._gravity(k)
            return [
                *algorithms.rnea(links, cs, qd, qdd, gravity),
                *algorithms.rnea(links, cs, zeros, zeros, gravity),
                *momentum_terms(links, cs, qd),
            ]

        return self._kernel("monitor", terms, qd=self.n, qdd=self.n)
