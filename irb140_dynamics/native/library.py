"""Shared libraries compiled from C source, kept in a cache folder: the only place the
package starts a C compiler (a process).

``library(source)`` returns the path of the library built from ``source``: from the cache
when it is there, else compiled by ``$CC`` (``cc`` or ``gcc`` else) at the lowest CPU priority.
Libraries are kept in ``$IRB140_CACHE`` (else ``$XDG_CACHE_HOME`` or ``~/.cache``,
``irb140_dynamics/kernels``), named by a hash of their source, flags, compiler and machine,
and by a digest of their own bytes, checked before one is used (a truncated library could
crash the process): another process, or the next run, loads them without compiling. A
compile runs in a working folder of the cache folder, removed when it ends, also when the
interpreter exits during it; one left by a process that was killed is removed by a later
compile once it is ``STALE_AFTER`` old. A cache folder that others can write to is refused.
A header the sources include (the extensions' Python and NumPy API) is precompiled there
once (``precompiled_header``), the bulk of a small kernel's compile.
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import os
import platform
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

FLAGS = ("-std=c99", "-O2", "-fPIC", "-shared", "-ffp-contract=off", "-fno-fast-math", "-fno-builtin")
COMPILE_TIMEOUT = 600.0  # s: a long chain's mass matrix on a busy machine, at the lowest priority
NICENESS = 19  # of the compiler: the lowest CPU priority, so that a node's loop comes first
STALE_AFTER = 3600.0  # s: a working folder this old is no running compile's (see library)
WORKING_PREFIX = "build-"  # a compile's working folder in the cache folder


def c_compiler() -> str | None:
    return shutil.which(os.environ.get("CC") or "cc") or shutil.which("gcc")


def cache_dir() -> Path:
    base = os.environ.get("IRB140_CACHE") or os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "irb140_dynamics" / "kernels"


def library(source: str, flags: list[str] = (), header: tuple[str, str] | None = None) -> Path:
    """The shared library of ``source``, compiled unless cached; OSError or
    subprocess.SubprocessError when it cannot be.

    It is named by the key of what it is built from and the digest of its bytes
    (``<key>-<digest>.so``), written whole by an atomic rename and checked before it is
    returned: a file that does not match its name (cut short by a full disk, a crash before
    its data reached the disk, an edit) is removed and compiled again. The compile runs in a
    working folder of its own, removed when it ends; a working folder left by a process
    killed during a compile is removed here once older than STALE_AFTER (a compile lasts
    COMPILE_TIMEOUT at most, so it is no running one's). ``header``: (name, text) of a
    header ``source`` includes, put on the include path with its precompiled form
    (``precompiled_header``)."""
    cc = c_compiler()
    if cc is None:
        raise OSError("no C compiler")
    parts = [source, cc, *FLAGS, *flags, *(header or ()), sys.platform, platform.machine()]
    key = hashlib.sha256("\0".join(parts).encode()).hexdigest()[:32]
    folder = cache_dir()
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    _private(folder)
    path = _cached(folder, key)
    if path is not None:
        _private(path)
        return path
    _remove_stale(folder)
    made = None if header is None else precompiled_header(folder, cc, *header, flags)
    if made is not None:
        flags = [f"-I{made}", *flags]
    work = Path(tempfile.mkdtemp(prefix=WORKING_PREFIX, dir=folder))
    try:
        (work / "kernel.c").write_text(source)
        if header is not None and made is None:  # the header read beside the source
            (work / header[0]).write_text(header[1])
        _compile([cc, *FLAGS, *flags, "kernel.c", "-o", "kernel.so", "-lm"], work)
        built = work / "kernel.so"
        path = folder / f"{key}-{_digest(built.read_bytes())}.so"
        os.replace(built, path)  # atomic: another process sees the whole library or none
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return path


def precompiled_header(folder: Path, cc: str, name: str, text: str, flags: list[str]) -> Path | None:
    """The folder in ``folder`` holding the header ``name`` (``text``) and its precompiled
    form (GCC's ``name.gch``), or None when the compiler makes none: a source that includes
    ``name``, compiled with ``-I`` that folder, is then compiled without parsing what
    ``text`` includes (Python's and NumPy's headers, the most of a small kernel's compile),
    to the same library. Made once, like a library: whole by an atomic rename, named by its
    key and the precompiled form's size (checked: one cut short is made again)."""
    key = hashlib.sha256("\0".join([name, text, cc, *FLAGS, *flags]).encode()).hexdigest()[:32]
    for entry in sorted(os.listdir(folder)):
        if entry.startswith(f"header-{key}-"):
            made = folder / entry
            if (made / name).is_file() and entry == f"header-{key}-{_size(made / f'{name}.gch')}":
                return made
            shutil.rmtree(made, ignore_errors=True)
    work = Path(tempfile.mkdtemp(prefix=WORKING_PREFIX, dir=folder))
    try:
        (work / name).write_text(text)
        compile_flags = [flag for flag in FLAGS if flag != "-shared"]
        try:
            _compile([cc, *compile_flags, *flags, "-x", "c-header", name, "-o", f"{name}.gch"], work)
        except subprocess.SubprocessError:  # (an OSError, the interpreter exiting included, stops the compile)
            return None
        made = folder / f"header-{key}-{_size(work / f'{name}.gch')}"
        try:
            os.rename(work, made)  # atomic; another process's, made meanwhile, stands
        except OSError:
            if not (made / name).is_file():
                return None
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return made


def _size(path: Path) -> int:
    """The size of ``path`` in bytes, -1 when there is none."""
    try:
        return path.stat().st_size
    except OSError:
        return -1


def _compile(args: list[str], work: Path) -> None:
    """Run the compiler ``args`` in ``work`` (see _Builds); SubprocessError if it fails,
    TimeoutExpired after COMPILE_TIMEOUT."""
    process = _BUILDS.start(args, work)
    try:
        _, error = process.communicate(timeout=COMPILE_TIMEOUT)
    except subprocess.TimeoutExpired:
        _BUILDS.kill(process)
        process.wait()
        raise
    finally:
        _BUILDS.done(process)
    if process.returncode != 0:
        if _BUILDS.stopped:  # killed at exit: no compile follows
            raise OSError("the interpreter is exiting")
        raise subprocess.SubprocessError(error.decode(errors="replace").strip()[:300])


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

    @property
    def stopped(self) -> bool:
        return self._stopped

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
