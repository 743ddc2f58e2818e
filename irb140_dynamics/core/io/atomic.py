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
