"""Errors as one line of text: what a log line, a service answer or a tool's error shows;
counts with their nouns (``counted``); a value out of its choices (``check_choice``).

One line, under 300 characters: the rest of a long message (a URDF element, a list of
names) is cut and the cut marked with '...'."""

from __future__ import annotations

LINE_LIMIT = 299  # characters: an error line is shorter than 300


def counted(count: int, noun: str) -> str:
    """'1 point', '2 points', '1,234 points': a count and its noun, singular for one."""
    return f"{count:,} {noun}{'' if count == 1 else 's'}"


def one_line(error: BaseException | str, limit: int = LINE_LIMIT) -> str:
    """The error's text on one line (white space runs made one space), cut to ``limit``."""
    text = " ".join(str(error).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def check_choice(name: str, value, choices) -> None:
    """ValueError naming ``name`` unless ``value`` is one of ``choices`` (a string setting)."""
    if value not in choices:
        raise ValueError(f"{name}: must be one of {', '.join(choices)}; got {value!r}")
