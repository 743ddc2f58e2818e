"""The kernels of one model, by name (``RECIPES``), each traced and compiled on first use.

The payload (merged into the last link) and gravity are not folded into the code: their
13 numbers (m, h, I about the origin of the last link; g) are the kernels' last argument
``k``, whose default is the model's own. Only the zero ones are folded (as the rest of the
model is), so models that differ only in payload or gravity share their compiled code
(cached per arm and pattern of zeros, see ``_arm``): changing the payload mass, or moving
it along the flange axis, compiles nothing; the code is as short as a fully folded one.
"""

from __future__ import annotations

import threading
import time
import types
from dataclasses import dataclass, replace
from functools import cached_property, lru_cache

from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.algorithms.momentum import momentum_terms
from irb140_dynamics.core.algorithms.regressor import rigid_body_regressor
from irb140_dynamics.core.codegen import native
from irb140_dynamics.core.codegen.array_code import compile_into
from irb140_dynamics.core.codegen.program import Program, traced, with_friction
from irb140_dynamics.core.codegen.python_code import compile_python
from irb140_dynamics.core.model.rigid_body import ZERO3, ZERO6

ARMS_CACHED = 16  # arms whose compiled code is kept (a model change is a new arm)


class Kernel:
    """One traced algorithm (``program``, see program) and its forms: ``scalar`` on floats,
    ``array`` on NumPy arrays, ``into`` on NumPy arrays writing the outputs into given
    arrays (see array_code), and ``native`` (bound kernels): None, or the same program
    compiled as C (see native), a function of the argument groups but k as float64 arrays
    returning an array or None (then the Python form answers); asked for once the Python
    form has run native.PROMOTE_AFTER times, or by ``prepare``."""

    native = None
    _calls = 0

    def __init__(self, program: Program, full_matrix: int = 0):
        self.program, self.full_matrix = program, full_matrix  # full_matrix: n to write M whole in C
        self._unbound, self.constants = self, None
        self.source, self.scalar, self.array = compile_python(program)

    def bound(self, constants: tuple) -> Kernel:
        """This kernel with ``k`` defaulting to ``constants`` (one model's payload and gravity)."""
        kernel = object.__new__(Kernel)
        kernel._unbound, kernel.constants = self, constants
        kernel.program, kernel.full_matrix, kernel.source = self.program, self.full_matrix, self.source
        kernel.scalar, kernel.array = (_with_default(fn, constants) for fn in (self.scalar, self.array))
        return kernel

    def used(self) -> None:
        """Count a call of the Python form; the PROMOTE_AFTER-th asks for the native one.
        Each call compares the count it wrote: with threads, a count can be written twice
        (then asked for twice, harmless) but none is skipped, so it is asked for."""
        calls = self._calls = self._calls + 1
        if calls == native.PROMOTE_AFTER and self.constants is not None and native.enabled():
            native.COMPILER.request(self)

    @cached_property
    def _compiled_into(self) -> tuple:
        if self._unbound is not self:
            _, into, written = self._unbound._compiled_into
            return None, _with_default(into, self.constants), written
        return compile_into(self.program, scalars=("k",))

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


@dataclass(frozen=True)
class Recipe:
    """How a kernel is traced: ``algorithm(arm, cs, *groups, k)`` -> outputs, the argument
    groups after q (each n long, ``wrench`` 6), and whether its outputs are M's upper
    triangle (the C form then writes M whole)."""

    algorithm: object
    groups: tuple[str, ...] = ()
    matrix: bool = False


def _rnea(arm, cs, qd, qdd, k):
    return algorithms.rnea(arm.links_with(k), cs, qd, qdd, arm.gravity_of(k))


def _rnea_wrench(arm, cs, qd, qdd, wrench, k):
    force, moment = algorithms.flange_wrench(arm.flange, wrench[:3], wrench[3:])
    return algorithms.rnea(arm.links_with(k), cs, qd, qdd, arm.gravity_of(k), force, moment)


def _gravity(arm, cs, k):
    zeros = [0.0] * arm.n
    return algorithms.rnea(arm.links_with(k), cs, zeros, zeros, arm.gravity_of(k))


def _coriolis(arm, cs, qd, k):
    return algorithms.rnea(arm.links_with(k), cs, qd, [0.0] * arm.n, (0.0, 0.0, 0.0))


def _mass_matrix(arm, cs, k):
    M = algorithms.crba(arm.links_with(k), cs)
    return [M[i][j] for i in range(arm.n) for j in range(i, arm.n)]


def _coriolis_matrix(arm, cs, qd, k):
    return [x for row in algorithms.christoffel_coriolis(arm.links_with(k), cs, qd) for x in row]


def _regressor(arm, cs, qd, qdd, k):
    # column by column, as the algorithm computes them: then the array form (see
    # array_code) keeps few intermediates alive (29 buffers for the IRB-140, not 138)
    Y = rigid_body_regressor(arm.links_with(k), cs, qd, qdd, arm.gravity_of(k))
    return [x for column in zip(*Y) for x in column]


def _momentum(arm, cs, qd, k):
    return momentum_terms(arm.links_with(k), cs, qd)


def _monitor(arm, cs, qd, qdd, k):
    links, gravity, zeros = arm.links_with(k), arm.gravity_of(k), [0.0] * arm.n
    return [
        *algorithms.rnea(links, cs, qd, qdd, gravity),
        *algorithms.rnea(links, cs, zeros, zeros, gravity),
        *momentum_terms(links, cs, qd),
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
}
# rnea with the model's joint friction inside (its coefficients appended to k); the model's
# plain ``rnea`` when it has none
WITH_FRICTION = "rnea_with_friction"


class Kernels:
    """The kernels of a model, by name (``RECIPES``, and WITH_FRICTION): ``kernels.rnea``,
    ``kernels.kernel("rnea")``, each made on first use."""

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
        self._friction = model.friction
        self._lock = threading.Lock()  # one kernel of a name, also when threads ask at once

    @property
    def angles(self) -> list[float]:
        """The joints' angle offsets (theta_i = q_i + offset_i); None for a prismatic joint."""
        return self._arm.angles

    def compiled(self, *names: str) -> bool:
        """Whether these kernels' code exists already (shared with a model of the same arm):
        then using them compiles nothing."""
        return all(self._arm.has(self._arm_name(name)) for name in names)

    def kernel(self, name: str) -> Kernel:
        """The kernel ``name``, made on first use and kept (also as the attribute ``name``)."""
        kernel = vars(self).get(name)
        if kernel is not None:
            return kernel
        if name not in RECIPES and name != WITH_FRICTION:
            raise AttributeError(f"no kernel {name!r}: one of {', '.join([*RECIPES, WITH_FRICTION])}")
        if name == WITH_FRICTION and self._friction is None:
            kernel = vars(self)[name] = self.kernel("rnea")  # the same kernel: one native form
            return kernel
        with self._lock:
            kernel = vars(self).get(name)
            if kernel is not None:
                return kernel
            constants = self.constants
            if name == WITH_FRICTION:
                f = self._friction
                coulomb = f.coulomb.tolist() + [float(f.smoothing_velocity)] if f.coulomb.any() else []
                constants += tuple(f.viscous.tolist() + coulomb)
            kernel = vars(self)[name] = self._arm.kernel(self._arm_name(name)).bound(constants)
        return kernel

    __getattr__ = kernel  # called for the names not made yet only: then an attribute

    def _arm_name(self, name: str) -> str:
        if name != WITH_FRICTION:
            return name
        if self._friction is None:
            return "rnea"
        return "rnea_coulomb" if self._friction.coulomb.any() else "rnea_viscous"


NATIVE_KERNELS = (WITH_FRICTION, "gravity_torques", "mass_matrix")  # what rnea, gravity, mass_matrix call


@dataclass(frozen=True)
class Preparation:
    """What ``prepare`` did: ``native``, whether the kernels asked for are native now;
    ``seconds``, how long it took (tracing, compiling or loading from the cache, checking);
    ``compiling``, whether a compile goes on in the background after the timeout (the
    Python form answers meanwhile, the native one from when it is ready)."""

    native: bool
    seconds: float
    compiling: bool = False


def prepare(model, timeout: float | None = None, names: tuple[str, ...] = NATIVE_KERNELS) -> Preparation:
    """Make ``model``'s kernels ``names`` native now: trace them, compile them as C (or load
    them from the cache) and check them, waiting at most ``timeout`` seconds (None: until
    done). After the timeout the compile goes on in the background. Without a compiler, or
    with IRB140_NATIVE=0, the kernels are traced (their Python form ready) and native is
    False. Safe from any thread; a kernel native already costs nothing."""
    start = time.monotonic()
    kernels = kernels_of(model)
    wanted = [kernels.kernel(name) for name in names]
    missing = [kernel for kernel in wanted if kernel.native is None]
    if native.enabled():  # code of the same arm compiled before: bound at once, no queue
        missing = [kernel for kernel in missing if not native.COMPILER.bind_built(kernel)]
    compiling = False
    if missing and native.enabled():
        left = None if timeout is None else max(0.0, timeout - (time.monotonic() - start))
        compiling = not native.COMPILER.compile_now(missing, left)
    done = all(kernel.native is not None for kernel in wanted)
    return Preparation(done, time.monotonic() - start, compiling and not done)


_MAKING = threading.Lock()  # one Kernels per model, also when threads ask for it at once


def kernels_of(model) -> Kernels:
    """The model's kernels, made on first use and kept with the model (models are immutable,
    so they never go stale; a changed model is a new model, with kernels of its own)."""
    kernels = model.__dict__.get("_kernels")
    if kernels is not None:
        return kernels
    with _MAKING:
        kernels = model.__dict__.get("_kernels")
        if kernels is None:
            kernels = model.__dict__["_kernels"] = Kernels(model)
        return kernels


@lru_cache(maxsize=ARMS_CACHED)
def _arm(links, flange, nonzero: tuple[bool, ...]) -> ArmKernels:
    return ArmKernels(links, flange, nonzero)


@dataclass(frozen=True)
class _Flange:
    """What algorithms.flange_wrench reads of a model."""

    flange: object


class ArmKernels:
    """The kernels of an arm (its links, the last one's inertia left out), traced once each
    on first use; the last link's inertia and gravity come from the argument ``k``, its
    nonzero ones of the 13 numbers (``nonzero``), the others are zero."""

    def __init__(self, links, flange, nonzero: tuple[bool, ...]):
        self.n = len(links)
        self.links = links
        self.flange = _Flange(flange)
        self.nonzero = nonzero
        self.angles = [None if link.prismatic else link.theta_offset for link in links]
        self._kernels: dict[str, Kernel] = {}
        self._lock = threading.RLock()  # one trace of a kernel, also when threads ask at once

    def has(self, name: str) -> bool:
        return name in self._kernels

    def kernel(self, name: str) -> Kernel:
        """The kernel ``name`` of RECIPES, or ``rnea_viscous`` / ``rnea_coulomb`` (rnea with
        friction, see program.with_friction), traced and compiled on first use."""
        kernel = self._kernels.get(name)
        if kernel is not None:
            return kernel
        with self._lock:
            kernel = self._kernels.get(name)
            if kernel is not None:
                return kernel
            if name in ("rnea_viscous", "rnea_coulomb"):
                program = with_friction(self.kernel("rnea").program, "qd", coulomb=name == "rnea_coulomb")
                kernel = Kernel(program)
            else:
                recipe = RECIPES[name]
                inputs = {group: 6 if group == "wrench" else self.n for group in recipe.groups}
                inputs["k"] = sum(self.nonzero)
                algorithm = recipe.algorithm
                program = traced(name, lambda *args: algorithm(self, *args), inputs, self.angles)
                kernel = Kernel(program, self.n if recipe.matrix else 0)
            self._kernels[name] = kernel
        return kernel

    def _spread(self, k) -> tuple:
        """The 13 numbers from the nonzero ones in k."""
        given = iter(k)
        return tuple(next(given) if used else 0.0 for used in self.nonzero)

    def links_with(self, k):
        """The links with the last one's inertia from k."""
        x = self._spread(k)
        return self.links[:-1] + (replace(self.links[-1], m=x[0], h=x[1:4], I=x[4:10]),)

    def gravity_of(self, k):
        return self._spread(k)[10:13]
