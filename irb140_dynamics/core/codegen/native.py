"""A kernel's program compiled as C (see ``c_code``), for the single-state public functions.

Compiled without contraction or fast-math (``-ffp-contract=off``: no fused multiply-add)
and with cos, sin and tanh left to libm, the C performs the very operations of the Python
form in the same order, so its results are the same, bit for bit. That is checked before a
native kernel is used: on random inputs it must equal the Python kernel exactly, else it is
never used. It is built as a CPython extension module (Python.h and NumPy's headers) whose
functions take NumPy arrays directly; where Python.h is missing, as a plain library called
through ctypes (slower per call, same numbers).

Compiling takes a C compiler (``$CC``, ``cc`` or ``gcc``), so no call of a kernel waits
for it: one background thread compiles the kernels asked for (the compiler at the lowest
CPU priority), a kernel whose Python form has run ``PROMOTE_AFTER`` times, or those that
``kernels.prepare`` asks for first and waits for, and calls use the native code once it is
ready. Without a compiler, or with ``IRB140_NATIVE=0``, everything stays in Python; so does
a kernel whose compile fails in any way (no usable cache folder, a ``$CC`` that is not a
compiler): the caller never sees it. Libraries are kept in ``$IRB140_CACHE`` (else
``$XDG_CACHE_HOME`` or ``~/.cache``, ``irb140_dynamics/kernels``), named by a hash of their
source, flags, compiler and machine, and by a digest of their own bytes, checked before one
is loaded (a truncated library could crash the process): another process, or the next run,
loads them without compiling. A compile runs in a working folder of the cache folder,
removed when it ends, also when the interpreter exits during it; one left by a process that
was killed is removed by a later compile once it is ``STALE_AFTER`` old.
"""

from __future__ import annotations

import array
import atexit
import collections
import contextlib
import ctypes
import hashlib
import importlib.machinery
import importlib.util
import os
import platform
import random
import shutil
import signal
import subprocess
import sys
import sysconfig
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from irb140_dynamics.core.codegen import c_code
from irb140_dynamics.core.codegen.layout import whole_matrix

PROMOTE_AFTER = 1000  # calls of a kernel's Python form before it is compiled
CHECKS = 20  # random inputs on which the native code must equal the Python code exactly
FLAGS = ("-std=c99", "-O2", "-fPIC", "-shared", "-ffp-contract=off", "-fno-fast-math", "-fno-builtin")
COMPILE_TIMEOUT = 600.0  # s: a long chain's mass matrix on a busy machine, at the lowest priority
NICENESS = 19  # of the compiler: the lowest CPU priority, so that a node's loop comes first
STALE_AFTER = 3600.0  # s: a working folder this old is no running compile's (see library)
WORKING_PREFIX = "build-"  # a compile's working folder in the cache folder
FUNCTIONS_KEPT = 64  # compiled kernels kept for the next model of the same arm
_FLOAT64 = np.dtype(float)


def enabled() -> bool:
    return os.environ.get("IRB140_NATIVE", "1") != "0" and compiler() is not None


def compiler() -> str | None:
    return shutil.which(os.environ.get("CC") or "cc") or shutil.which("gcc")


def cache_dir() -> Path:
    base = os.environ.get("IRB140_CACHE") or os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "irb140_dynamics" / "kernels"


def library(source: str, flags: list[str] = ()) -> Path:
    """The shared library of ``source``, compiled unless cached; OSError or
    subprocess.SubprocessError when it cannot be.

    It is named by the key of what it is built from and the digest of its bytes
    (``<key>-<digest>.so``), written whole by an atomic rename and checked before it is
    returned: a file that does not match its name (cut short by a full disk, a crash before
    its data reached the disk, an edit) is removed and compiled again. The compile runs in a
    working folder of its own, removed when it ends; a working folder left by a process
    killed during a compile is removed here once older than STALE_AFTER (a compile lasts
    COMPILE_TIMEOUT at most, so it is no running one's)."""
    cc = compiler()
    if cc is None:
        raise OSError("no C compiler")
    parts = [source, cc, *FLAGS, *flags, sys.platform, platform.machine()]
    key = hashlib.sha256("\0".join(parts).encode()).hexdigest()[:32]
    folder = cache_dir()
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    _private(folder)
    path = _cached(folder, key)
    if path is not None:
        _private(path)
        return path
    _remove_stale(folder)
    work = Path(tempfile.mkdtemp(prefix=WORKING_PREFIX, dir=folder))
    try:
        (work / "kernel.c").write_text(source)
        built = work / "kernel.so"
        process = _BUILDS.start([cc, *FLAGS, *flags, "kernel.c", "-o", built.name, "-lm"], work)
        try:
            _, error = process.communicate(timeout=COMPILE_TIMEOUT)
        except subprocess.TimeoutExpired:
            _BUILDS.kill(process)
            process.wait()
            raise
        finally:
            _BUILDS.done(process)
        if process.returncode != 0:
            raise subprocess.SubprocessError(error.decode(errors="replace").strip()[:300])
        path = folder / f"{key}-{_digest(built.read_bytes())}.so"
        os.replace(built, path)  # atomic: another process sees the whole library or none
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return path


def _private(path: Path) -> None:
    """OSError unless ``path`` is this user's and writable by nobody else: a library loaded
    from a folder that others can write to would run their code in this process."""
    status = path.stat()
    if (hasattr(os, "getuid") and status.st_uid != os.getuid()) or status.st_mode & 0o022:
        raise OSError(f"{path}: not private to this user (owner or group/other write): not used")


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:16]


def _cached(folder: Path, key: str) -> Path | None:
    """The library of ``key`` in ``folder`` whose bytes match its name; the others of
    ``key`` are removed (loading one could crash the process)."""
    try:
        names = sorted(name for name in os.listdir(folder) if name.startswith(f"{key}-") and name.endswith(".so"))
    except OSError:  # no cache folder (yet), or not a folder
        return None
    for name in names:
        path = folder / name
        try:
            intact = name == f"{key}-{_digest(path.read_bytes())}.so"
        except OSError:
            continue
        if intact:
            return path
        with contextlib.suppress(OSError):
            path.unlink()
    return None


def _remove_stale(folder: Path) -> None:
    """Remove the working folders in ``folder`` older than STALE_AFTER."""
    with contextlib.suppress(OSError):
        for entry in os.scandir(folder):
            if entry.name.startswith(WORKING_PREFIX):
                with contextlib.suppress(OSError):
                    if time.time() - entry.stat(follow_symlinks=False).st_mtime > STALE_AFTER:
                        shutil.rmtree(entry.path, ignore_errors=True)


class _Builds:
    """The compiler processes running in this process, each in a process group of its own
    (the driver's children too), killed at interpreter exit, whose working folders are then
    removed: a daemon thread is stopped at exit wherever it is, so it could not. After exit
    has begun, no compile starts. A forked child has none (its parent's are its parent's)."""

    def __init__(self):
        self._reset()
        os.register_at_fork(after_in_child=self._reset)
        atexit.register(self.stop)

    def _reset(self) -> None:
        self._lock = threading.Lock()
        self._running: dict[subprocess.Popen, Path] = {}  # process -> its working folder
        self._stopped = False

    def start(self, args: list[str], work: Path) -> subprocess.Popen:
        with self._lock:
            if self._stopped:
                raise OSError("the interpreter is exiting")
            process = subprocess.Popen(
                args,
                cwd=work,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                start_new_session=True,
            )
            self._running[process] = work
        with contextlib.suppress(OSError):  # a node's loop comes first; the group: the driver's
            os.setpriority(os.PRIO_PGRP, process.pid, NICENESS)  # children started already too
        return process

    def done(self, process: subprocess.Popen) -> None:
        with self._lock:
            self._running.pop(process, None)

    @staticmethod
    def kill(process: subprocess.Popen) -> None:
        if process.poll() is None:
            with contextlib.suppress(OSError):
                os.killpg(process.pid, signal.SIGKILL)

    def stop(self) -> None:
        with self._lock:
            self._stopped = True
            running = list(self._running.items())
        for process, work in running:
            self.kill(process)
            with contextlib.suppress(subprocess.SubprocessError, OSError):
                process.wait(timeout=5.0)
            shutil.rmtree(work, ignore_errors=True)


_BUILDS = _Builds()


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
    """The compiled form of ``program`` (compiled or loaded from the cache): (bind, lengths,
    shape) with ``bind(constants: bytes)`` the kernel with those constants, a function of
    the argument groups but k (1-D float64 arrays of ``lengths``) -> an array shaped
    ``shape``, or None (anything else, or not finite)."""
    lengths = [length for group, length in program.groups if group != "k"]
    source, _, outputs = c_code.kernel_source(program, full_matrix)
    shape = (full_matrix, full_matrix) if full_matrix else (outputs,)
    include = headers()
    if include is None:
        function = load(source)
        return (lambda constants: CtypesKernel(function, constants, lengths, shape)), lengths, shape
    versions = "\0".join([source, sys.version, np.__version__, *include])
    name = "k" + hashlib.sha256(versions.encode()).hexdigest()[:24]
    extension = c_code.extension_source(program, name, full_matrix)
    path = library(extension, [f"-I{folder}" for folder in include])
    module = importlib.util.module_from_spec(
        importlib.util.spec_from_loader(name, importlib.machinery.ExtensionFileLoader(name, str(path)))
    )
    module.__spec__.loader.exec_module(module)
    return module.bind, lengths, shape


def load(source: str):
    """The C function ``kernel`` of ``source`` through ctypes (compiled or loaded from the cache)."""
    function = ctypes.PyDLL(str(library(source))).kernel  # the GIL stays held: a call is short
    function.restype = ctypes.c_int
    function.argtypes = (ctypes.c_char_p, ctypes.c_char_p, ctypes.c_void_p)
    return function


def same_as_python(native, python, lengths: list[int], full_matrix: int) -> bool:
    """Does ``native`` (arrays -> array or None) give exactly the Python kernel's numbers
    (bound: k defaulted)?"""
    rng = random.Random(140)
    for _ in range(CHECKS):
        args = [[rng.uniform(-4.0, 4.0) for _ in range(length)] for length in lengths]
        want = list(python(*args))
        if full_matrix:
            want = whole_matrix(want, full_matrix)
        got = native(*(np.array(a) for a in args))
        if got is None or got.tobytes() != array.array("d", want).tobytes():  # bits: -0.0 is not 0.0
            return False
    return True


class _Compiler:
    """One background thread compiling the kernels asked for, one at a time."""

    def __init__(self):
        self._built: dict[tuple, tuple | None] = {}  # (program, full_matrix) -> build() (None: failed), the newest last
        self._restart()
        # a forked child has no worker thread, and its lock may have been held by another thread
        os.register_at_fork(after_in_child=self._restart)

    def _restart(self) -> None:
        self._ready = threading.Condition(threading.Lock())
        self._requests: collections.deque = collections.deque()  # kernels and Events, the next first
        self._thread: threading.Thread | None = None

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

    def bind_built(self, kernel) -> bool:
        """Make ``kernel`` native here and now with code compiled already for its program (a
        model that differs from one compiled before only in payload or gravity): True if so,
        False when there is none yet (or it gives other numbers). Never waits for the worker."""
        built = self._built.get((kernel.program, kernel.full_matrix))
        if built is None or kernel.constants is None:
            return False
        bind, lengths, _ = built
        found = bind(array.array("d", kernel.constants).tobytes())
        if not same_as_python(found, kernel.scalar, lengths, kernel.full_matrix):
            return False
        kernel.native = found
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
                kernel.native = self._native(kernel)
            except Exception:  # never let the worker die: the Python form stays in use
                kernel.native = None

    def _native(self, kernel):
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
        bind, lengths, _ = built
        native = bind(array.array("d", kernel.constants).tobytes())
        return native if same_as_python(native, kernel.scalar, lengths, full_matrix) else None


COMPILER = _Compiler()
