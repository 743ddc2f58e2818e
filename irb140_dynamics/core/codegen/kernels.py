"""An arm's kernels as an object a caller holds: ``Kernels(model)``, or ``kernels_of(model)``,
the one the public verbs use (as Pinocchio keeps what a call needs in ``Data``, apart from
its ``Model``).

The payload (merged into the last link, or the ``flange_joint``'s) and gravity are not folded
into the code: the kernels' last argument ``k`` holds gravity and the numbers that link's
inertia (m, h, I about its origin) reaches once the links are regrouped (``_regrouping``:
its own and those it moves into the links below), whose default is the model's own. Only
the zero ones are folded (as the rest of the model is), so models that differ only in
payload or gravity share their traced code (cached per arm and pattern of zeros, see
``_arm``): changing the payload mass, or moving it along the flange axis, traces nothing;
the code is as short as a fully folded one.

The kernels' native form (C) is made by a compiler outside the core (see
``irb140_dynamics.native_hook``): ``prepare`` asks for it now, and a kernel whose arm's Python
forms have run PROMOTE_AFTER times (over the models sharing that code, a call of many states
counting once) asks for it in the background; the calls use it once it is on the kernel
(``Kernel.native``, and ``Kernel.native_batch`` for many states at once).
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, replace
from functools import cached_property, lru_cache, partial

from irb140_dynamics import native_hook
from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.algorithms.mimic import Coordinates, coupling
from irb140_dynamics.core.algorithms.regrouping import MOMENTS, Affine, affine, pattern_of
from irb140_dynamics.core.codegen.array_code import compile_into
from irb140_dynamics.core.codegen.program import Program, traced, with_friction
from irb140_dynamics.core.codegen.python_code import compile_python
from irb140_dynamics.core.codegen.recipes import RECIPES, WITH_FRICTION
from irb140_dynamics.core.model.per_model import PerModel
from irb140_dynamics.core.model.rigid_body import ZERO3, ZERO6

ARMS_CACHED = 16  # arms whose traced code is kept (a model change is a new arm)
PROMOTE_AFTER = 1000  # calls of an arm's kernel's Python forms before it is made native in the background
NATIVE_KERNELS = (WITH_FRICTION, "gravity_torques", "mass_matrix")  # what rnea, gravity, mass_matrix call


class Trace:
    """One algorithm traced on one arm (``program``, see program) and its Python forms,
    each ``bind(constants)``: the source on floats and on NumPy arrays, and on first use the
    form writing into given arrays (see array_code). ``calls``: of those forms, by every
    model of the arm (see ``Kernel.used``)."""

    def __init__(self, program: Program, full_matrix: int = 0):
        self.program, self.full_matrix = program, full_matrix  # full_matrix: n to write M whole in C
        self.source, self.bind_scalar, self.bind_array = compile_python(program)
        self.calls = 0

    @cached_property
    def writing(self) -> tuple:
        """(bind, written): see array_code.compile_into."""
        _, bind, written = compile_into(self.program, scalars=("k",))
        return bind, written


class Kernel:
    """One kernel of one model: its arm's ``Trace`` with ``k`` defaulting to the model's
    ``constants`` (the numbers the payload's link's inertia reaches, and gravity). ``scalar`` on floats, ``array`` on NumPy arrays,
    ``into`` writing into given arrays; ``native``: None, or the same program compiled as C
    (put here by a compiler, see native_hook), a function of the argument groups but k as
    float64 arrays returning an array or None (then the Python form answers);
    ``native_batch``: None, or that C over N states, a function of the groups as (length, N)
    float64 columns returning an (N, outputs) array (N whole matrices for a ``full_matrix``
    kernel) or None (then ``array`` answers for them all)."""

    native = None
    native_batch = None

    def __init__(self, trace: Trace, constants: tuple):
        self.trace, self.constants = trace, constants
        self.program, self.full_matrix, self.source = trace.program, trace.full_matrix, trace.source
        self.scalar, self.array = trace.bind_scalar(constants), trace.bind_array(constants)
        self._asked = False

    def used(self) -> None:
        """Count a call of a Python form (``scalar``, or ``array`` on a batch of states: once)
        on the arm's count: from the PROMOTE_AFTER-th on, the kernel's next call asks for its
        native form, once. So a model of a busy arm (a search making a model per payload
        mass) asks on its first call, and gets its native form as soon as the compiler has
        bound the arm's code to its constants (nothing compiled again). With threads, a
        kernel may ask twice (harmless), never not at all."""
        calls = self.trace.calls = self.trace.calls + 1
        if calls >= PROMOTE_AFTER and not self._asked:
            self._asked = True
            compiler = native_hook.installed()
            if compiler is not None:
                compiler.promote(self)
            else:  # the compile room loaded off the caller's thread: no call waits for it
                threading.Thread(target=_promote, args=(self,), name="irb140-promote", daemon=True).start()

    @cached_property
    def _into(self):
        bind, _ = self.trace.writing
        return bind(self.constants)

    @property
    def into(self):
        """(out, q, ...) -> None: the outputs at the indices ``written`` into out[index]
        (arrays of N states), compiled on first use."""
        return self._into

    @property
    def written(self) -> list[int]:
        """The indices of the outputs ``into`` writes: those not folded to constants."""
        return self.trace.writing[1]


def _promote(kernel: Kernel) -> None:
    """Ask the compiler (its room loaded here the first time) for ``kernel``'s native form."""
    try:
        compiler = native_hook.compiler()
        if compiler is not None:
            compiler.promote(kernel)
    except Exception:  # the Python form stays in use
        pass


@dataclass(frozen=True)
class Preparation:
    """What ``prepare`` did: ``native``, whether the kernels asked for are native now;
    ``seconds``, how long it took (tracing, compiling or loading from the cache, checking);
    ``compiling``, whether a compile goes on in the background after the timeout (the
    Python form answers meanwhile, the native one from when it is ready); ``reason``, why
    they are not native when they are not (e.g. 'IRB140_NATIVE=0', 'no C compiler')."""

    native: bool
    seconds: float
    compiling: bool = False
    reason: str | None = None


def _named(name: str) -> cached_property:
    """The attribute ``kernels.<name>``: ``kernels.kernel(name)``, looked up once."""
    attribute = cached_property(lambda self: self.kernel(name))
    attribute.__doc__ = f"The kernel {name!r} (see recipes.RECIPES)."
    return attribute


class Kernels:
    """The kernels of one model, by name (``recipes.RECIPES``, and WITH_FRICTION):
    ``kernels.rnea``, or ``kernels.kernel("rnea")``, each traced on first use (or shared with
    a model of the same arm, see ``_arm``). A caller may hold its own (``Kernels(model)``);
    the public verbs use ``kernels_of(model)``."""

    rnea = _named("rnea")
    rnea_wrench = _named("rnea_wrench")
    gravity_torques = _named("gravity_torques")
    coriolis = _named("coriolis")
    mass_matrix = _named("mass_matrix")
    coriolis_matrix = _named("coriolis_matrix")
    regressor = _named("regressor")
    momentum = _named("momentum")
    monitor = _named("monitor")
    rnea_with_friction = _named(WITH_FRICTION)
    rnea_derivatives = _named("rnea_derivatives")
    forward_dynamics_derivatives = _named("forward_dynamics_derivatives")
    forward_dynamics_qdd = _named("forward_dynamics_qdd")
    inverse_mass_matrix = _named("inverse_mass_matrix")

    def __init__(self, model):
        self.n = model.n
        self.shape = (model.n,)  # of a state array, compared on the hot paths
        self.links = links = algorithms.chain(model)  # the whole model's, for other number types
        self.gravity = model.gravity
        at = model.carrier  # the payload's link: the last one's, or the flange_joint's
        carrier = links[at]
        arm = links[:at] + (replace(carrier, m=0.0, h=ZERO3, I=ZERO6),) + links[at + 1 :]
        # plain floats: a NumPy scalar (a URDF inertial turned by NumPy) would make every
        # operation it enters several times slower
        x = tuple(float(v) for v in (carrier.m, *carrier.h, *carrier.I))
        regrouping = _regrouping(arm, at, pattern_of(x))
        kinds = tuple(i if j in MOMENTS else None for i, j in regrouping.entries)  # a link's moments of inertia
        layout, self.constants = inputs_of(regrouping.values(x) + tuple(float(g) for g in model.gravity), kinds)
        self._arm = _arm(regrouping, model.flange, layout, coupling(model), at)
        self._friction = model.friction
        self._made: dict[str, Kernel] = {}
        self._lock = threading.Lock()  # one kernel of a name, also when threads ask at once

    @property
    def angles(self) -> list[float]:
        """The joints' angle offsets (theta_i = q_i + offset_i); None for a prismatic joint."""
        return self._arm.angles

    def traced(self, *names: str) -> bool:
        """Whether these kernels' code exists already (shared with a model of the same arm):
        then using them traces nothing."""
        return all(self._arm.has(self._arm_name(name)) for name in names)

    def kernel(self, name: str) -> Kernel:
        """The kernel ``name``, made on first use and kept."""
        kernel = self._made.get(name)
        if kernel is not None:
            return kernel
        if name not in RECIPES and name != WITH_FRICTION:
            raise KeyError(f"no kernel {name!r}: one of {', '.join([*RECIPES, WITH_FRICTION])}")
        if name == WITH_FRICTION and self._friction is None:
            kernel = self._made[name] = self.kernel("rnea")  # the same kernel: one native form
            return kernel
        with self._lock:
            kernel = self._made.get(name)
            if kernel is None:
                constants = self.constants
                if (name == WITH_FRICTION or RECIPES[name].friction) and self._friction is not None:
                    f = self._friction
                    coulomb = f.coulomb.tolist() + [float(f.smoothing_velocity)] if f.coulomb.any() else []
                    constants += tuple(f.viscous.tolist() + coulomb)
                kernel = self._made[name] = Kernel(self._arm.trace(self._arm_name(name)), constants)
        return kernel

    def is_native(self, *names: str) -> bool:
        """Whether these kernels run native now."""
        return all(self.kernel(name).native is not None for name in names)

    def prepare(self, timeout: float | None = None, names: tuple[str, ...] = NATIVE_KERNELS) -> Preparation:
        """Make the kernels ``names`` native now: trace them, have them compiled as C (or
        loaded from the cache) and checked, waiting at most ``timeout`` seconds (None: until
        done). After the timeout the compile goes on in the background. Without a compiler,
        or with IRB140_NATIVE=0, the kernels are traced (their Python form ready) and native
        is False. Safe from any thread; kernels native already cost nothing."""
        start = time.monotonic()
        wanted = [self.kernel(name) for name in names]
        compiler = native_hook.compiler()
        reason = "no compiler installed" if compiler is None else compiler.unavailable()
        compiling = False
        if reason is None and any(kernel.native is None for kernel in wanted):
            left = None if timeout is None else max(0.0, timeout - (time.monotonic() - start))
            compiling = not compiler.make_native(wanted, left)
        done = all(kernel.native is not None for kernel in wanted)
        if not done and reason is None:
            reason = "compiling" if compiling else "not compiled (the compile failed or differed from Python)"
        return Preparation(done, time.monotonic() - start, compiling and not done, None if done else reason)

    def ready(self, names: tuple[str, ...] = NATIVE_KERNELS) -> bool:
        """Whether ``prepare(names=names)`` would return at once: the kernels traced already
        (by this model or another of the same arm), and native or never to be (no compiler,
        IRB140_NATIVE=0). Those whose arm has native code built already are made native on
        the way (cheap, no compile)."""
        if not self.traced(*names):
            return False
        wanted = [self.kernel(name) for name in names]
        if all(kernel.native is not None for kernel in wanted):
            return True
        compiler = native_hook.compiler()
        return compiler is None or compiler.unavailable() is not None or compiler.bind_built(wanted)

    def _arm_name(self, name: str) -> str:
        if name in RECIPES and RECIPES[name].friction and self._friction is not None:
            return f"{name}_coulomb" if self._friction.coulomb.any() else f"{name}_viscous"
        if name != WITH_FRICTION:
            return name
        if self._friction is None:
            return "rnea"
        return "rnea_coulomb" if self._friction.coulomb.any() else "rnea_viscous"


VERBS_KERNELS = PerModel(Kernels)  # the kernels the public verbs use, by model: kept here, not in the model


def kernels_of(model) -> Kernels:
    """The model's kernels that the public verbs use, made on first use and kept while the
    model lives (models are immutable, so they never go stale; a changed model is a new
    model, with kernels of its own). The hot paths read ``VERBS_KERNELS.kept`` inline
    first: ``kept.get(id(model)) or kernels_of(model)``."""
    return VERBS_KERNELS.get(model)


def prepare(model, timeout: float | None = None, names: tuple[str, ...] = NATIVE_KERNELS) -> Preparation:
    """Make ``model``'s kernels ``names`` native now (see Kernels.prepare): what ``rnea``,
    ``gravity`` and ``mass_matrix`` run from then on."""
    return kernels_of(model).prepare(timeout, names)


def inputs_of(numbers: tuple[float, ...], kinds: tuple = ()) -> tuple[tuple[int | None, ...], tuple[float, ...]]:
    """(each number's index in ``k``, None for the constant 0; k's values): an input per
    nonzero number, but equal numbers of one kind (``kinds[j]``, not None: a link's moments of
    inertia) take the same, so that the traces fold their difference (the tracer's
    x - x = 0): a body symmetric about its joint's axis turns at no cost
    (``rotations.turned_about``), and needs no angle."""
    layout: list[int | None] = []
    values: list[float] = []
    for j, x in enumerate(numbers):
        kind = kinds[j] if j < len(kinds) else None
        same = [] if kind is None else [e for e in range(j) if kinds[e] == kind and numbers[e] == x]
        if x == 0.0:
            layout.append(None)
        elif same:
            layout.append(layout[same[0]])
        else:
            layout.append(len(values))
            values.append(x)
    return tuple(layout), tuple(values)


@lru_cache(maxsize=ARMS_CACHED)
def _regrouping(links, at: int, like: tuple[float, ...]) -> Affine:
    """The arm's links regrouped with link ``at``'s inertia free (``regrouping.affine``), by
    the choices made for ``like`` (``regrouping.pattern_of``): one per arm and pattern."""
    return affine(links, at, like)


@lru_cache(maxsize=ARMS_CACHED)
def _arm(regrouping: Affine, flange, layout: tuple[int | None, ...], coupled, carrier: int) -> ArmKernels:
    return ArmKernels(regrouping, flange, layout, coupled, carrier)


@dataclass(frozen=True)
class _Flange:
    """What algorithms.flange_wrench reads of a model."""

    flange: object


class ArmKernels(Coordinates):
    """The traces of an arm (its links, the carrier's inertia left out), each made once on
    first use. ``links`` are regrouped (``algorithms.regrouping``): joint torques come out
    the same, a link's own wrench does not (``Kernels.links`` are the model's); the numbers
    the carrier's inertia reaches (``regrouping.entries``), then gravity, come from the
    argument ``k``: the j-th is k[layout[j]], or 0 where layout[j] is None (see
    ``inputs_of``)."""

    def __init__(self, regrouping: Affine, flange, layout: tuple[int | None, ...], coupled, carrier: int):
        self.carrier = carrier  # the link the payload and a flange wrench are on
        # every kernel gives joint-space quantities (or, the regressor, reads no inertia):
        # the same from fewer nonzero inertial parameters
        self.regrouping = regrouping
        self.flange = _Flange(flange)
        self.layout = layout
        self.inputs = 1 + max((j for j in layout if j is not None), default=-1)  # k's length
        self._traces: dict[str, Trace] = {}
        self._lock = threading.RLock()  # one trace of a kernel, also when threads ask at once
        Coordinates.__init__(self, self.regrouping.base, coupled)

    def has(self, name: str) -> bool:
        return name in self._traces

    def trace(self, name: str) -> Trace:
        """The trace ``name`` of RECIPES, or ``rnea_viscous`` / ``rnea_coulomb`` (rnea with
        friction, see program.with_friction), made on first use."""
        trace = self._traces.get(name)
        if trace is not None:
            return trace
        with self._lock:
            trace = self._traces.get(name)
            if trace is not None:
                return trace
            if name in ("rnea_viscous", "rnea_coulomb"):
                program = with_friction(self.trace("rnea").program, "qd", coulomb=name == "rnea_coulomb")
                trace = Trace(program)
            else:
                base, friction = _friction_kind(name)
                recipe = RECIPES[base]
                inputs = {group: 6 if group == "wrench" else self.n for group in recipe.groups}
                inputs["k"] = self.inputs + {None: 0, "viscous": self.n, "coulomb": 2 * self.n + 1}[friction]
                algorithm = partial(recipe.algorithm, friction=friction) if recipe.friction else recipe.algorithm
                program = traced(name, lambda *args: algorithm(self, *args), inputs, self.angles, self.mimic_angles)
                if recipe.matrices:
                    program = replace(program, matrices=recipe.matrices)
                trace = Trace(program, self.n if recipe.matrix else 0)
            self._traces[name] = trace
        return trace

    def _spread(self, k) -> tuple:
        """The numbers (the carrier's entries, gravity) from their inputs in k."""
        return tuple(0.0 if j is None else k[j] for j in self.layout)

    def links_with(self, k):
        """The regrouped links with the numbers the carrier's inertia reaches from k."""
        return self.regrouping.links(self._spread(k)[:-3])

    def gravity_of(self, k):
        return self._spread(k)[-3:]


def _friction_kind(name: str) -> tuple[str, str | None]:
    """(recipe, friction kind) of an arm's kernel name: ``<recipe>_viscous`` or
    ``<recipe>_coulomb`` for a recipe that takes friction."""
    for kind in ("viscous", "coulomb"):
        base = name.removesuffix(f"_{kind}")
        if base != name and base in RECIPES and RECIPES[base].friction:
            return base, kind
    return name, None
