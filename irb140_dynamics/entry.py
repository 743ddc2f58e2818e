"""How every executable of the package starts and ends: the nodes and the tools, as console
scripts, ``ros2 run`` and ``python -m``.

Light on purpose (the standard library only: no NumPy, no rclpy, nothing of the package),
and importing it changes nothing. An executable calls ``start`` before its heavy imports,
then ``finish(main)``:

- From ``start`` on, SIGINT and SIGTERM (and the kind's other stop signals) are noted, never
  raised: a Ctrl-C while NumPy, rclpy or MuJoCo load cannot cut an extension module's
  start-up half-way (a traceback, or the interpreter killing itself with SIGINT as it
  exits). Every executable runs OpenBLAS on one thread unless OPENBLAS_NUM_THREADS or
  OMP_NUM_THREADS says otherwise: its linear algebra is on small matrices, where
  OpenBLAS's threads spin while they wait (on a busy machine identify took 5 to 20 times
  the CPU time of one thread), and starting them doubles NumPy's import (0.17 against
  0.09 CPU-s): a node beside a 1 kHz controller wants neither. An exception nobody catches is one line
  ('<name>: cannot start: ...' for a missing module, '<name>: internal error: ...'
  otherwise) and exit status 1; IRB140_TRACEBACK=1 shows the traceback.
- ``finish(main)`` calls main() and exits with its status. A node gets Python's own
  handling back first (KeyboardInterrupt, which ``ros.runtime.spin.run`` makes a clean
  stop); a stop signal noted while it started ends it there: exit 0, no line, the stop
  asked for. A tool takes the noted signals itself (``take_noted_signals``: ``tools.cli.run``
  says '<tool>: interrupted' and exits 128 + the signal, 130 after Ctrl-C; ``record``
  takes them as a stop request). Once main() has returned, the stop signals are ignored:
  Python puts its default handlers back as it exits, and a late Ctrl-C would otherwise
  print a traceback or change the status.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Callable
from typing import NamedTuple, NoReturn


class Kind(NamedTuple):
    """What sort of executable: which signals stop it, and how it ends when one came while
    it started."""

    stop_signals: tuple[int, ...]
    stopped_early_status: int | None  # exit status without a line; None: main() decides


NODE = Kind((signal.SIGINT, signal.SIGTERM), 0)
TOOL = Kind((signal.SIGINT, signal.SIGTERM), None)
RECORDER = Kind((signal.SIGINT, signal.SIGTERM, signal.SIGHUP), None)  # record: SIGHUP stops it too

BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")
INTERRUPTED = 128 + signal.SIGINT  # a tool's exit status after Ctrl-C


class _Program:
    """The executable this process runs, from ``start`` on: its stop signals noted, not raised."""

    def __init__(self, name: str, kind: Kind):
        self.name = name
        self.kind = kind
        self.noted: list[int] = []
        self.previous = {s: signal.signal(s, self._note) for s in kind.stop_signals}

    def _note(self, signum: int, _frame) -> None:
        self.noted.append(signum)

    def give_back_signals(self) -> None:
        for s, handler in self.previous.items():
            signal.signal(s, handler)

    def ignore_signals(self) -> None:
        for s in self.kind.stop_signals:
            signal.signal(s, signal.SIG_IGN)

    def uncaught(self, kind: type[BaseException], error: BaseException, traceback) -> None:
        """sys.excepthook: an exception nobody caught, as one line."""
        if os.environ.get("IRB140_TRACEBACK"):
            sys.__excepthook__(kind, error, traceback)
            return
        text = " ".join(str(error).split())
        if issubclass(kind, ImportError):
            line = f"{self.name}: cannot start: {text or kind.__name__}"
        else:
            line = f"{self.name}: internal error: {kind.__name__}: {text}"
        print(line, file=sys.stderr, flush=True)


_program: _Program | None = None  # set by start(), in an executable's process only


def start(name: str, kind: Kind) -> None:
    """The executable ``name`` begins (before its heavy imports): see the module's docstring."""
    global _program
    if "numpy" not in sys.modules and not set(BLAS_THREAD_VARIABLES) & set(os.environ):
        os.environ["OPENBLAS_NUM_THREADS"] = "1"
    _program = _Program(name, kind)
    sys.excepthook = _program.uncaught


def finish(main: Callable[[], int | None]) -> NoReturn:
    """Run the started executable's ``main()`` and exit with its status (SystemExit's code
    when it raises one); see the module's docstring."""
    program = _program
    if program is None:
        raise RuntimeError("entry.finish() without entry.start()")
    try:
        status = _main_status(program, main)
    finally:
        program.ignore_signals()
    _clear_interrupted_string_code()
    raise SystemExit(status)


def _clear_interrupted_string_code() -> None:
    """A KeyboardInterrupt that passed through code run from a string (a library's
    ``exec("from numpy import *")`` while it is imported, SciPy's) leaves CPython a flag by
    which the interpreter kills itself with SIGINT as it exits (status -2, not main()'s),
    however the exception was handled afterwards. Running a string to its end clears it."""
    exec("")


def _main_status(program: _Program, main: Callable[[], int | None]) -> int | str | None:
    early = program.kind.stopped_early_status
    if early is not None:
        program.give_back_signals()
        if program.noted:
            return early
    try:
        return main()
    except SystemExit as stop:
        return stop.code
    except KeyboardInterrupt:  # raised before main() had its own handling in place
        if early is not None:
            return early
        print(f"{program.name}: interrupted", file=sys.stderr, flush=True)
        return INTERRUPTED


def take_noted_signals() -> list[int]:
    """The stop signals that came since the executable started, in order, now the caller's
    to act on (and forgotten here). Empty in a process no executable started (a test)."""
    if _program is None:
        return []
    taken = list(_program.noted)
    del _program.noted[: len(taken)]
    return taken
