"""Input files checked before they are parsed: a regular file (not a device, a pipe or a
folder), no larger than a limit, and text (UTF-8, no NUL byte). A refusal is a ValueError
of one line naming the file; the limits are module constants, and the environment variable
IRB140_MAX_FILE_BYTES raises or lowers them all at once (bytes)."""

from __future__ import annotations

import os
import stat
from pathlib import Path

MAX_TEXT_BYTES = 64 * 2**20  # a URDF with inline meshes stays far below; a params file is kilobytes
ENVIRONMENT_LIMIT = "IRB140_MAX_FILE_BYTES"


class InputFileError(ValueError):
    """An input file that cannot be read as the text it should be: one line, naming it."""


def size_limit(default: int = MAX_TEXT_BYTES) -> int:
    """The size limit in force: IRB140_MAX_FILE_BYTES when set to a positive integer."""
    text = os.environ.get(ENVIRONMENT_LIMIT, "").strip()
    if text.isdigit() and int(text) > 0:
        return int(text)
    return default


def read_text_file(path, what: str = "file", max_bytes: int | None = None) -> str:
    """The text of ``path``, or InputFileError saying why not (missing, not a regular file,
    too large, not text)."""
    path = Path(path)
    limit = size_limit() if max_bytes is None else max_bytes
    try:
        info = path.stat()
    except FileNotFoundError:
        raise InputFileError(f"{path}: no such {what}") from None
    except OSError as error:
        raise InputFileError(f"{path}: cannot read the {what}: {error.strerror or error}") from None
    if stat.S_ISDIR(info.st_mode):
        raise InputFileError(f"{path}: is a folder, not a {what}")
    if not stat.S_ISREG(info.st_mode):
        raise InputFileError(f"{path}: not a regular file (a device, pipe or socket), refused as a {what}")
    if info.st_size > limit:
        raise InputFileError(
            f"{path}: {info.st_size:,} bytes, over the {limit:,}-byte limit for a {what} (set {ENVIRONMENT_LIMIT} to raise it)"
        )
    try:
        with open(path, "rb") as stream:
            data = stream.read(limit + 1)
    except OSError as error:
        raise InputFileError(f"{path}: cannot read the {what}: {error.strerror or error}") from None
    if len(data) > limit:
        raise InputFileError(
            f"{path}: over the {limit:,}-byte limit for a {what} (set {ENVIRONMENT_LIMIT} to raise it)"
        )
    if b"\0" in data:
        raise InputFileError(f"{path}: binary data (a NUL byte), not a {what}")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise InputFileError(f"{path}: not UTF-8 text at byte {error.start}, not a {what}") from None
