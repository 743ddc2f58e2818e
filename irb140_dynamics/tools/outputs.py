"""A tool's output files, written whole or not at all, and all together.

Each file is first written to a temporary file in its target folder (its mode as the umask
makes it) and fsync'd; ``commit`` renames them all into place, all or none
(``core.io.atomic.replace_all``: when one cannot be, the files already replaced are put
back), with signals held off meanwhile, and fsyncs their folders. Until then nothing is
visible under the target names; ``discard`` (or an exception leaving the ``with`` block,
Ctrl-C included) removes the temporary files and any folder made for them. An error names
the path as the user typed it, never a temporary file.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Callable
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import BinaryIO

from irb140_dynamics.core.io.atomic import new_temporary, replace_all
from irb140_dynamics.tools.cli import Interrupts, ToolError

HELD = {signal.SIGINT, signal.SIGTERM}


@contextmanager
def signals_held() -> None:
    """SIGINT and SIGTERM wait (pending) until the block ends."""
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, HELD)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


class Outputs:
    def __init__(self, interrupts: Interrupts | None = None):
        self.interrupts = interrupts
        self._staged: list[tuple[Path, Path, str]] = []  # (temporary, target, as typed)
        self._created: list[Path] = []  # folders made for the outputs, outermost first

    def __enter__(self) -> Outputs:
        return self

    def __exit__(self, kind, *_) -> None:
        if kind is not None or self._staged:
            self.discard()

    def directory(self, target: Path, typed: str) -> Path:
        """Make the folder ``target`` (and its missing parents), undone by discard()."""
        missing = []
        path = Path(target)
        while not os.path.lexists(path):
            missing.append(path)
            path = path.parent
        for folder in reversed(missing):
            try:
                with signals_held():
                    folder.mkdir()
                    self._created.append(folder)
            except OSError as error:
                raise ToolError(f"{typed}: cannot create {folder} ({error.strerror})") from None
        return target

    def stage(self, target: Path, typed: str, write: Callable[[BinaryIO], None]) -> None:
        """Write ``target`` by ``write(stream)`` into a temporary file beside it."""
        target = Path(target)
        try:
            with signals_held():  # the name is known before the file can be left behind
                descriptor, name = new_temporary(target.parent)
                self._staged.append((name, target, typed))
            with os.fdopen(descriptor, "wb") as stream:
                write(stream)
                stream.flush()
                os.fsync(stream.fileno())
        except OSError as error:
            raise ToolError(f"{typed}: cannot write ({error.strerror or error})") from None

    def text(self, target: Path, typed: str, text: str) -> None:
        self.stage(target, typed, lambda stream: stream.write(text.encode()))

    def commit(self) -> list[str]:
        """Rename every staged file into place; what was written, as typed. A Ctrl-C from
        here on no longer interrupts: the tool has finished its work."""
        with signals_held():
            if self.interrupts is not None:
                if self.interrupts.received is not None:  # a Ctrl-C that library code swallowed
                    self.discard()
                    raise KeyboardInterrupt
                self.interrupts.finished = True
            try:
                replace_all((temporary, target) for temporary, target, _ in self._staged)
            except OSError as error:
                typed = next((t for _, target, t in self._staged if str(target) == error.filename), "output")
                self.discard()
                raise ToolError(f"{typed}: cannot write ({error.strerror or error}); nothing written") from None
            written = [typed for _, _, typed in self._staged]
            for folder in {target.parent for _, target, _ in self._staged}:
                _fsync_directory(folder)
            self._staged, self._created = [], []
        return written

    def discard(self) -> None:
        with signals_held():
            for temporary, _, _ in self._staged:
                with suppress(OSError):
                    temporary.unlink()
            for folder in reversed(self._created):
                with suppress(OSError):
                    folder.rmdir()
            self._staged, self._created = [], []


def _fsync_directory(folder: Path) -> None:
    try:
        descriptor = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return
    try:
        os.fsync(descriptor)
    except OSError:
        pass
    finally:
        os.close(descriptor)
