"""What every command-line tool does alike: bad input in one line, arguments and output
paths checked before any work, Ctrl-C at any moment one line and exit 130.

A Ctrl-C while the tool starts (its imports) is noted by the entry (irb140_dynamics.entry)
and acted on here, when ``run`` begins.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import signal
import sys
from collections.abc import Callable
from pathlib import Path

from irb140_dynamics.core.errors import LINE_LIMIT, one_line  # noqa: F401 (the tools import them from here)
from irb140_dynamics.entry import take_noted_signals
from irb140_dynamics.tools.progress import open_line


class ToolError(Exception):
    """An error the tool reports in one line (exit status 1)."""

    status = 1


class BadArgument(ToolError):
    """A bad argument found after parsing (an unknown parameter name): one line, exit status 2."""

    status = 2


class Parser(argparse.ArgumentParser):
    """argparse, its errors in one line (``prog: error: ...; see --help``, status 2)."""

    def error(self, message: str):
        self.exit(2, one_line(f"{self.prog}: error: {message}; see --help") + "\n")


def number(
    low: float | None = None, high: float | None = None, *, above: bool = False, integer: bool = False
) -> Callable[[str], float]:
    """An argparse type: a finite number (an integer with ``integer``) within [low, high]
    (above low with ``above``); NaN, inf and anything outside refused."""

    def parse(text: str):
        try:
            value = int(text, 10) if integer else float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not {'an integer' if integer else 'a number'}: {text!r}") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
        if low is not None and (value <= low if above else value < low):
            raise argparse.ArgumentTypeError(f"must be {'>' if above else '>='} {low:g}, got {text}")
        if high is not None and value > high:
            raise argparse.ArgumentTypeError(f"must be <= {high:g}, got {text}")
        return value

    parse.__name__ = "integer" if integer else "number"
    return parse


def shown(path) -> str:
    """A path as typed, its middle left out when it is long (an error line stays short)."""
    text = str(path)
    return text if len(text) <= 80 else f"{text[:38]}...{text[-39:]}"


def _refuse(path: str, why: str) -> ToolError:
    return ToolError(f"{shown(path)}: {why}")


def _why(error: OSError) -> str:
    return error.strerror or type(error).__name__


def _probe_directory(path: str, directory: Path) -> None:
    """Create and remove a file in ``directory``: the only sure test that a file can be
    written there (root passes os.access everywhere; /proc refuses anyway)."""
    import tempfile

    try:
        descriptor, name = tempfile.mkstemp(prefix=".irb140-probe-", dir=directory)
    except OSError as error:
        raise _refuse(path, f"cannot write in {shown(directory)} ({_why(error)})") from None
    os.close(descriptor)
    os.unlink(name)


def _name_fits(path: str, target: Path, directory: Path) -> None:
    try:
        limit = os.pathconf(directory, "PC_NAME_MAX")
    except (OSError, ValueError):
        limit = 255
    if len(os.fsencode(target.name)) > limit:
        raise _refuse(path, f"file name longer than {limit} bytes")


def output_file(path: str) -> Path:
    """The file ``path`` (relative to the working directory) can be written, whole, by
    rename: its folder exists and takes a new file, and it is not there or a regular file.
    Returns it absolute; a ToolError names ``path`` as typed."""
    if not path or path.endswith(os.sep):
        raise _refuse(path or "''", "not a file name")
    target = Path(os.path.abspath(path))
    if os.path.lexists(target):
        if target.is_dir():
            raise _refuse(path, "is a directory")
        if not target.is_file():
            raise _refuse(path, "exists and is not a regular file")
    directory = target.parent
    if not directory.exists():
        raise _refuse(path, f"no such directory {shown(directory)}")
    if not directory.is_dir():
        raise _refuse(path, f"{shown(_nearest_file(directory))} is not a directory")
    _name_fits(path, target, directory)
    _probe_directory(path, directory)
    return target


def output_directory(path: str, must_be_new: bool = False) -> Path:
    """The directory ``path`` can be written in: it exists (and ``must_be_new`` is False),
    or its nearest existing ancestor is a directory that takes new entries. Absolute."""
    if not path:
        raise _refuse("''", "not a directory name")
    target = Path(os.path.abspath(path))
    if os.path.lexists(target):
        if must_be_new:
            raise _refuse(path, "exists already; give a new name")
        if not target.is_dir():
            raise _refuse(path, "exists and is not a directory")
        _probe_directory(path, target)
        return target
    ancestor = target.parent
    while not os.path.lexists(ancestor):
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise _refuse(path, f"{shown(ancestor)} is not a directory")
    _name_fits(path, target, target.parent if target.parent.exists() else ancestor)
    _probe_directory(path, ancestor)
    return target


def files_in(directory: Path, typed: str, names) -> list[tuple[str, Path]]:
    """The files ``names`` a tool writes in the folder ``directory`` (from
    ``output_directory``; ``typed`` as the user gave it), as (as typed, absolute path)
    pairs: each one absent or a regular file, else a ToolError before any work."""
    files = [(os.path.normpath(os.path.join(typed, name)), directory / name) for name in names]
    for written_as, path in files:
        if os.path.lexists(path) and not path.is_file():
            raise _refuse(written_as, "is a directory" if path.is_dir() else "exists and is not a regular file")
    return files


def check_model_paths(args: argparse.Namespace) -> None:
    """The model's input files (``--params-file``, ``--urdf``) exist, before any work."""
    for path in (getattr(args, "params_file", None), getattr(args, "urdf", None)):
        if path:
            input_path(path)


def input_path(path: str, what: str = "file") -> Path:
    """An existing input (file or directory), absolute; a ToolError names ``path`` as typed."""
    if not path:
        raise _refuse("''", f"not a {what} name")
    target = Path(os.path.abspath(path))
    if not target.exists():
        raise _refuse(path, "no such file or directory")
    return target


def refuse_input_as_output(inputs, outputs) -> None:
    """ToolError, before any work, when an output is one of the inputs by any path (as
    typed, through a linked folder, a hard link), or lies in an input that is a folder (a
    bag): writing it would replace or change the input. ``inputs`` and ``outputs``: (as
    shown to the user, absolute path or None) pairs."""
    given = [(shown_as, path) for shown_as, path in inputs if path is not None]
    for written_as, output in outputs:
        for shown_as, path in given if output is not None else ():
            if _same_file(path, output):
                raise ToolError(
                    f"{shown(written_as)}: would replace the input {shown(shown_as)}; give the output another name"
                )
            if _inside(output, path):
                raise ToolError(
                    f"{shown(written_as)}: would write into the input {shown(shown_as)}; give the output another place"
                )


def _same_file(a: Path, b: Path) -> bool:
    try:
        if os.path.samefile(a, b):
            return True
    except OSError:  # the output is not there yet
        pass
    return os.path.realpath(a) == os.path.realpath(b)


def _inside(path: Path, folder: Path) -> bool:
    """``path`` lies in the folder ``folder`` (followed through links)."""
    if not os.path.isdir(folder):
        return False
    return os.path.realpath(path).startswith(os.path.join(os.path.realpath(folder), ""))


def _nearest_file(path: Path) -> Path:
    """The ancestor of ``path`` that exists (a file, when a path goes on 'under' one)."""
    while not os.path.lexists(path):
        path = path.parent
    return path


class Interrupts:
    """SIGINT and SIGTERM raise KeyboardInterrupt once; any later one is ignored (the
    clean-up after the first runs to its end); ``calm()`` ignores them all (a commit that
    must finish)."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self):
        self.received: int | None = None
        self.finished = False
        self._previous = {}

    def _on_signal(self, signum, _frame) -> None:
        if self.received is not None or self.finished:
            return
        self.received = signum
        raise KeyboardInterrupt

    def install(self) -> None:
        if self._previous or threading_is_not_main():
            return
        for s in self.SIGNALS:
            self._previous[s] = signal.signal(s, self._on_signal)

    def restore(self) -> None:
        """The handlers from before (the entry's, when the tool is the program: it ignores
        the signals once main() has returned)."""
        for s, handler in self._previous.items():
            signal.signal(s, handler)
        self._previous = {}

    @property
    def status(self) -> int:
        return 128 + int(self.received or signal.SIGINT)


def threading_is_not_main() -> bool:
    import threading

    return threading.current_thread() is not threading.main_thread()


@contextlib.contextmanager
def errors_as_bad_input():
    """Within it, an error (a ToolError, bad input, a defect of ours) exits with status 2,
    said as ``run`` says it: for a tool whose status 1 is an answer (load_diagram --check:
    outside). Ctrl-C and a closed standard output keep theirs."""
    try:
        yield
    except BrokenPipeError:
        raise
    except Exception as error:
        error.status = 2  # (read by _failed; a ToolError's class status, shadowed)
        raise


def run(tool: str, body: Callable[[Interrupts], int]) -> int:
    """``body(interrupts)`` -> exit status. A ToolError or bad input becomes one line
    'tool: error: ...' and status 1; Ctrl-C (or SIGTERM) one line 'tool: interrupted' and
    130 (143); a closed standard output (``tool | head``) nothing, and 141 as for SIGPIPE;
    the body's ``Outputs`` leave nothing behind in each case."""
    interrupts = Interrupts()
    try:
        interrupts.install()  # (a signal may come half-way: one handler ours, the other still the entry's)
        early = take_noted_signals()
        if early:  # Ctrl-C while the tool was starting: nothing done yet
            interrupts.received = early[0]
            raise KeyboardInterrupt
        return body(interrupts)
    except SystemExit as stop:  # argparse: --help (0), a bad argument (2, its line printed)
        interrupts.finished = True
        return stop.code if isinstance(stop.code, int) else 0
    except BaseException as error:  # noqa: BLE001  (sorted in _failed)
        interrupts.finished = True
        noted = take_noted_signals()  # the entry noted these before ours were in place: they came first
        if noted and isinstance(error, KeyboardInterrupt):
            interrupts.received = noted[0]
        return _failed(tool, error, interrupts)
    finally:
        interrupts.finished = True
        interrupts.restore()


def _failed(tool: str, error: BaseException, interrupts: Interrupts) -> int:
    """The one line and the exit status of a tool that ``error`` stopped."""
    if isinstance(error, KeyboardInterrupt) or interrupts.received is not None:
        # Ctrl-C, or what it became on its way up (NumPy's "initialization failed" ImportError)
        interrupts.received = interrupts.received or signal.SIGINT
        _say(f"{tool}: interrupted")
        return interrupts.status
    if isinstance(error, BrokenPipeError):  # `tool | head`: the reader has gone, as with SIGPIPE
        _quiet_stdout()
        return 128 + signal.SIGPIPE
    if isinstance(error, ToolError):
        _say(f"{tool}: error: {error}")
    elif isinstance(error, (ValueError, OSError, ArithmeticError, MemoryError, RecursionError)):
        _say(f"{tool}: error: {_describe(error)}")
    elif isinstance(error, Exception):  # a defect of ours: still one line, not a traceback
        if os.environ.get("IRB140_TRACEBACK"):  # for the developers
            raise error
        _say(f"{tool}: internal error: {type(error).__name__}: {error}")
    else:  # GeneratorExit and the like
        raise error
    return getattr(error, "status", 1)  # a ToolError's, or 2 from errors_as_bad_input


def _quiet_stdout() -> None:
    """Standard output to /dev/null: the interpreter's last flush then has no closed pipe to
    complain about (Python's documented way, "Note on SIGPIPE")."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # no real stdout (a test's capture)
        pass


def _describe(error: BaseException) -> str:
    if isinstance(error, OSError) and error.filename is not None:
        return f"{error.filename}: {_why(error)}"
    if isinstance(error, MemoryError):
        return "out of memory (the input is too large)"
    if isinstance(error, RecursionError):
        return "the input is nested too deeply"
    return str(error) or type(error).__name__


def _say(text: str) -> None:
    try:
        print(("\n" if open_line[0] else "") + one_line(text), file=sys.stderr, flush=True)
        open_line[0] = False
    except (OSError, ValueError):  # stderr closed
        pass
