"""Errors as one line of text: what a log line, a service answer or a tool's error shows."""

from __future__ import annotations


def one_line(error: BaseException | str) -> str:
    """The error's text with its line breaks made spaces."""
    return str(error).replace("\n", " ")
