"""A kernel's program compiled as C (see ``core.codegen.c_code``), made the kernel's native form.

Compiled without contraction or fast-math (``-ffp-contract=off``: no fused multiply-add)
and with cos, sin and tanh left to libm, the C performs the very operations of the Python
form in the same order, so its results are the same, bit for bit. That is checked before a
native form is put on a kernel: on random inputs it must equal the Python kernel exactly,
else it is never used. It is built as a CPython extension module (Python.h and NumPy's
headers) whose functions take NumPy arrays directly, one state (``Kernel.native``) or N
states in one call (``Kernel.native_batch``, the same C function in a loop, checked as
well); where Python.h is missing, as a plain library called through ctypes (slower per
call, same numbers; no batch form).

Compiling takes a C compiler (see ``library``), so no call of a kernel waits for it: one
background thread compiles the kernels asked for (a kernel whose Python form has run
``core.codegen.kernels.PROMOTE_AFTER`` times, or those that ``prepare`` asks for first and
waits for), and calls use the native form once it is on the kernel. Without a compiler, or
with ``IRB140_NATIVE=0``, everything stays in Python; so does a kernel whose compile fails in
any way (no usable cache folder, a ``$CC`` that is not a compiler): the caller never sees it.
"""

from __future__ import annotations

import array
import collections
import ctypes
import hashlib
import importlib.machinery
import importlib.util
import os
import random
import subprocess
import sys
import sysconfig
import threading
from pathlib import Path

import numpy as np

from irb140_dynamics.core.codegen import c_code
from irb140_dynamics.core.codegen.layout import whole_matrix
from irb140_dynamics.native.library import c_compiler, library

CHECKS = 20  # random inputs on which the native code must equal the Python code exactly
FUNCTIONS_KEPT = 64  # compiled kernels kept for the next model of the same arm
_FLOAT64 = np.dtype(float)


def unavailable() -> str | None:
    """Why no kernel is made native here, or None when kernels can be."""
    if os.environ.get("IRB140_NATIVE", "1") == "0":
        return "IRB140_NATIVE=0"
    if c_compiler() is None:
        return "no C compiler"
    return None


def enabled() -> bool:
    return unavailable() is None


class CtypesKernel:
    """A kernel loaded with ctypes, where no extension can be built (no Python.h): the
    extension's call (see c_code) in Python, with one model's constants."""

    def __init__(self, function, constants: bytes, lengths: list[int], shape: tuple[int, ...]):
        self._function, self._constants = function, constants
        self._lengths, self._shape = [(length,) for length in lengths], shape

    def __call__(self, *arrays):
        if len(arrays) != len(self._lengths) or not all(
            type(a) is np.ndarray and a.dtype is _FLOAT64 and a.shape == length
            for a, length in zip(arrays, self._lengths)
        ):
            return None
        out = np.empty(self._shape)
        inputs = b"".join(a.tobytes() for a in arrays)
        return out if self._function(inputs, self._constants, out.ctypes.data) == 0 else None


def headers() -> list[str] | None:
    """The include folders an extension is built with (Python's, NumPy's), or None when
    Python.h is missing (a Python without its development files)."""
    include = sysconfig.get_paths()["include"]
    if not (Path(include) / "Python.h").is_file():
        return None
    return [include, np.get_include()]


def build(program, full_matrix: int = 0):
    """The compiled form of ``program`` (compiled or loaded from the cache): (bind,
    bind_batch, lengths, shape) with ``bind(constants: bytes)`` the kernel with those
    constants, a function of the argument groups but k (1-D float64 arrays of ``lengths``)
    -> an array shaped ``shape``, or None (anything else, or not finite);
    ``bind_batch(constants)`` the same over N states (see c_code.extension_source), or None
    itself where there is none (ctypes, or a program of no state)."""
    lengths = [length for group, length in program.groups if group != "k"]
    source, _, outputs = c_code.kernel_source(program, full_matrix)
    shape = (full_matrix, full_matrix) if full_matrix else (outputs,)
    include = headers()
    if include is None:
        function = load(source)
        return (lambda constants: CtypesKernel(function, constants, lengths, shape)), None, lengths, shape
    versions = "\0".join([source, sys.version, np.__version__, *include])
    name = "k" + hashlib.sha256(versions.encode()).hexdigest()[:24]
    extension = c_code.extension_source(program, name, full_matrix)
    path = library(extension, [f"-I{folder}" for folder in include], c_code.EXTENSION_HEADER)
    module = importlib.util.module_from_spec(
        importlib.util.spec_from_loader(name, importlib.machinery.ExtensionFileLoader(name, str(path)))
    )
    module.__spec__.loader.exec_module(module)
    return module.bind, module.bind_batch if lengths else None, lengths, shape


def load(source: str):
    """The C function ``kernel`` of ``source`` through ctypes (compiled or loaded from the cache)."""
    function = ctypes.PyDLL(str(library(source))).kernel  # the GIL stays held: a call is short
    function.restype = ctypes.c_int
    function.argtypes = (ctypes.c_char_p, ctypes.c_char_p, ctypes.c_void_p)
    return function


def same_as_python(native, python, lengths: list[int], full_matrix: int, batch=None) -> bool:
    """Does ``native`` (arrays -> array, tuple of arrays or None) give exactly the Python
    kernel's numbers (bound: k defaulted)? And ``batch`` (when given: columns -> (N, ...)
    array or None) the same numbers for the same states at once, read through strides?"""
    rng = random.Random(140)
    states, wanted = [], []
    for _ in range(CHECKS):
        args = [[rng.uniform(-4.0, 4.0) for _ in range(length)] for length in lengths]
        want = list(python(*args))
        if full_matrix:
            want = whole_matrix(want, full_matrix)
        got = native(*(np.array(a) for a in args))
        if type(got) is tuple:  # a program's matrices (see c_code)
            got = np.concatenate([matrix.ravel() for matrix in got])
        expected = array.array("d", want).tobytes()
        if got is None or got.tobytes() != expected:  # bits: -0.0 is not 0.0
            return False
        states.append(args)
        wanted.append(expected)
    if batch is None:
        return True
    columns = [np.array([args[g] for args in states]).T for g in range(len(lengths))]  # views: strided
    got = batch(*columns)
    return type(got) is np.ndarray and got.tobytes() == b"".join(wanted)


class Compiler:
    """One background thread compiling the kernels asked for, one at a time (see
    ``irb140_dynamics.native_hook.Compiler``: what the core asks of it)."""

    def __init__(self):
        self._built: dict[tuple, tuple | None] = {}  # (program, full_matrix) -> build() (None: failed), the newest last
        self._restart()
        # a forked child has no worker thread, and its lock may have been held by another thread
        os.register_at_fork(after_in_child=self._restart)

    def _restart(self) -> None:
        self._ready = threading.Condition(threading.Lock())
        self._requests: collections.deque = collections.deque()  # kernels and Events, the next first
        self._thread: threading.Thread | None = None

    def unavailable(self) -> str | None:
        return unavailable()

    def promote(self, kernel) -> None:
        if enabled():
            self.request(kernel)

    def make_native(self, kernels, timeout: float | None) -> bool:
        """Those of ``kernels`` whose code of the same arm is built already made native at
        once; the others compiled before anything asked for earlier, waiting at most
        ``timeout`` s: True if all are done (or given up) in time."""
        if not enabled():
            return True
        missing = [kernel for kernel in kernels if kernel.native is None and not self._bind_built(kernel)]
        return not missing or self.compile_now(missing, timeout)

    def bind_built(self, kernels) -> bool:
        return all(kernel.native is not None or self._bind_built(kernel) for kernel in kernels)

    def _put(self, items: list, first: bool = False) -> None:
        """Queue ``items`` (at the front, in their order, with ``first``), the worker thread
        started to take them."""
        with self._ready:
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="irb140-native", daemon=True)
                self._thread.start()
            if first:
                self._requests.extendleft(reversed(items))
            else:
                self._requests.extend(items)
            self._ready.notify()

    def request(self, kernel) -> None:
        self._put([kernel])

    def wait(self, timeout: float | None = None) -> bool:
        """Until every kernel asked for so far (in this process) is compiled or given up:
        True if so in time. Nothing asked for: True at once."""
        done = threading.Event()
        self._put([done])
        return done.wait(timeout)

    def compile_now(self, kernels: list, timeout: float | None = None) -> bool:
        """Compile ``kernels`` before anything asked for earlier and wait until they are
        compiled or given up, at most ``timeout`` s: True if so in time (else they are
        compiled in the background)."""
        done = threading.Event()
        self._put([*kernels, done], first=True)
        return done.wait(timeout)

    def _bind_built(self, kernel) -> bool:
        """Make ``kernel`` native here and now with code compiled already for its program (a
        model that differs from one compiled before only in payload or gravity): True if so,
        False when there is none yet (or it gives other numbers). Never waits for the worker."""
        built = self._built.get((kernel.program, kernel.full_matrix))
        if built is None:
            return False
        forms = _bound(kernel, built)
        if forms is None:
            return False
        _put_on(kernel, forms)
        return True

    def _run(self) -> None:
        while True:
            with self._ready:
                while not self._requests:
                    self._ready.wait()
                kernel = self._requests.popleft()
            if isinstance(kernel, threading.Event):
                kernel.set()
                continue
            try:
                forms = self._native(kernel)
            except Exception:  # never let the worker die: the Python form stays in use
                forms = None
            _put_on(kernel, forms)

    def _native(self, kernel) -> tuple | None:
        """(native, batch) forms of ``kernel``, compiled or built already, checked; None if none."""
        program, full_matrix = kernel.program, kernel.full_matrix
        key = (program, full_matrix)
        if key not in self._built:
            try:
                built = build(program, full_matrix)
            except subprocess.TimeoutExpired:
                return None  # not kept: asked for again, it is compiled again
            except (OSError, ImportError, subprocess.SubprocessError):
                built = None
            if len(self._built) >= FUNCTIONS_KEPT:
                del self._built[next(iter(self._built))]
        else:
            built = self._built.pop(key)
        self._built[key] = built
        if built is None:
            return None
        return _bound(kernel, built)


def _bound(kernel, built: tuple) -> tuple | None:
    """(native, batch) forms of ``kernel`` (its constants bound) from ``built`` (see
    ``build``; batch None where there is none), or None when they differ from its Python form."""
    bind, bind_batch, lengths, _ = built
    constants = array.array("d", kernel.constants).tobytes()
    native = bind(constants)
    batch = None if bind_batch is None else bind_batch(constants)
    if not same_as_python(native, kernel.scalar, lengths, kernel.full_matrix, batch):
        return None
    return native, batch


def _put_on(kernel, forms: tuple | None) -> None:
    """``forms`` (native, batch) put on ``kernel`` (None: none), the batch form first: one
    that sees ``native`` sees the batch form too."""
    native, batch = (None, None) if forms is None else forms
    kernel.native_batch = batch
    kernel.native = native


COMPILER = Compiler()
