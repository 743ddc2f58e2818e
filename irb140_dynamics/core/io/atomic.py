"""Files written whole or not at all, several of them all or none, with the modes the user's
umask gives (0644 under umask 022, as ``open(path, "w")`` makes them).

A file is first written to a temporary file in its target folder (created with mode 0666,
the kernel applying the umask: ``tempfile.mkstemp``'s 0600 would leave the outputs readable
by their owner only), then renamed over its target. Several renames are made all or none
(``replace_all``): every destination is checked before the first, each file they replace
is kept aside (a hard link) until the last has succeeded, and put back when one fails.
"""

from __future__ import annotations

import errno
import os
import secrets
from collections.abc import Iterable
from contextlib import suppress
from pathlib import Path

TEMPORARY_PREFIX = ".irb140-"


def new_temporary(folder, suffix: str = ".tmp") -> tuple[int, Path]:
    """A new file in ``folder`` under a name no other has, open for writing: (descriptor,
    path). Its mode is 0666 less the umask, as for any file the user makes."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)
    for _ in range(100):
        path = Path(folder) / f"{TEMPORARY_PREFIX}{secrets.token_hex(6)}{suffix}"
        try:
            return os.open(path, flags, 0o666), path
        except FileExistsError:
            continue
    raise FileExistsError(errno.EEXIST, "no free temporary name", str(folder))


def write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` whole or not at all (a temporary file renamed)."""
    write_files({path: text.encode()})
    return Path(path)


def write_files(files: dict) -> list[Path]:
    """Write several files (path -> bytes) all whole or none: each to a temporary file in its
    folder, flushed to disk, then all renamed (``replace_all``). OSError names the file."""
    staged: list[tuple[Path, Path]] = []
    try:
        for path, data in files.items():
            target = Path(path)
            try:
                descriptor, temporary = new_temporary(target.parent)
            except OSError as error:  # named as the file asked for, not the temporary's name
                raise OSError(error.errno, error.strerror, str(target)) from None
            staged.append((temporary, target))
            with os.fdopen(descriptor, "wb") as stream:
                stream.write(data)
                stream.flush()
                os.fsync(stream.fileno())
        replace_all(staged)
    finally:
        for temporary, _ in staged:
            with suppress(OSError):
                temporary.unlink()
    return [target for _, target in staged]


def replace_all(renames: Iterable[tuple[Path, Path]]) -> None:
    """Rename each (temporary, target) pair, all or none: when one cannot be renamed, an
    OSError naming its target, every target then as it was (the temporaries not renamed
    are the caller's to remove)."""
    renames = [(Path(temporary), Path(target)) for temporary, target in renames]
    for _, target in renames:  # what would fail half-way, refused before the first rename
        if target.is_dir() and not target.is_symlink():
            raise IsADirectoryError(errno.EISDIR, "Is a directory", str(target))
    done: list[tuple[Path, Path | None]] = []  # (target, its old file kept aside or None)
    try:
        for temporary, target in renames:
            old = _keep_aside(target)
            try:
                os.replace(temporary, target)
            except OSError as error:
                _put_back(old, target)
                raise OSError(error.errno, error.strerror, str(target)) from None
            done.append((target, old))
    except BaseException:  # an OSError, or Ctrl-C half-way: every target as it was
        for target, old in reversed(done):
            with suppress(OSError):
                if old is None:
                    os.unlink(target)
                else:
                    os.replace(old, target)
        raise
    for _, old in done:
        if old is not None:
            with suppress(OSError):
                old.unlink()


def _put_back(old: Path | None, target: Path) -> None:
    """After a failed rename onto ``target``: its file kept aside by ``_keep_aside`` is its
    own again (a hard link is removed: rename(2) does nothing between two names of one file)."""
    if old is None:
        return
    with suppress(OSError):
        if os.path.lexists(target) and os.path.samestat(os.lstat(old), os.lstat(target)):
            old.unlink()
        else:
            os.replace(old, target)


def _keep_aside(target: Path) -> Path | None:
    """A second name for ``target``'s file (a hard link beside it), or None when there is
    no such file; where hard links are refused, the file itself is moved aside."""
    if not os.path.lexists(target):
        return None
    for _ in range(100):
        aside = target.parent / f"{TEMPORARY_PREFIX}{secrets.token_hex(6)}.old"
        try:
            os.link(target, aside, follow_symlinks=False)
            return aside
        except FileExistsError:
            continue
        except OSError:  # no hard links here: moved, the target absent until the rename
            os.rename(target, aside)
            return aside
    raise FileExistsError(errno.EEXIST, "no free temporary name", str(target.parent))
