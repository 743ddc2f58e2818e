"""Files written whole or not at all."""

from __future__ import annotations

import os
from pathlib import Path


def write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` whole or not at all (a temporary file renamed)."""
    path = Path(path)
    temporary = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        temporary.write_text(text)
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)
    return path


def write_files(files: dict) -> list[Path]:
    """Write several files (path -> bytes) all whole or none: each to a temporary file in its
    folder, flushed to disk, then all renamed. OSError names the file."""
    temporary: dict[Path, Path] = {}
    try:
        for path, data in files.items():
            target = Path(path)
            tmp = target.with_name(f".{target.name}.tmp{os.getpid()}")
            with open(tmp, "wb") as stream:
                temporary[target] = tmp
                stream.write(data)
                stream.flush()
                os.fsync(stream.fileno())
        for target, tmp in temporary.items():
            os.replace(tmp, target)
    finally:
        for tmp in temporary.values():
            tmp.unlink(missing_ok=True)
    return list(temporary)
