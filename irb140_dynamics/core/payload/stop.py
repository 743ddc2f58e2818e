"""When a long payload analysis stops early: cancelled (superseded: abandon it) or out of time
(finish now with what is proven so far).

The loops of the analysis (the search's sweeps in ``workspace``, the branch and bound of
``proof.certify``, the sampling) call ``out_of_time()`` between steps of bounded cost. It
raises ``Cancelled`` once the analysis was cancelled, and answers True once its deadline has
passed: the loop then ends as when its budget runs out, and the bounds it leaves are still
proven, only looser (the verdicts that need them say "unproven").

The stop in force belongs to the thread (a context variable), set by ``stopping``: a caller
cancels a worker's analysis by setting the Event it gave, without passing anything through
the analysis' functions. Outside any ``stopping`` nothing stops.
"""

from __future__ import annotations

import contextvars
import math
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass


class Cancelled(Exception):
    """The analysis was cancelled (a newer one superseded it): its result is not wanted."""


@dataclass
class Stop:
    """A cancel Event (None: never), a deadline (time.monotonic(); inf: none), and whether
    the deadline was met: ``ran_out`` (then what was computed is cut short)."""

    cancel: threading.Event | None = None
    deadline: float = math.inf
    ran_out: bool = False
    outer: Stop | None = None

    def out_of_time(self) -> bool:
        if self.cancel is not None and self.cancel.is_set():
            raise Cancelled("the analysis was cancelled")
        if self.outer is not None and self.outer.out_of_time() or time.monotonic() > self.deadline:
            self.ran_out = True
        return self.ran_out


_CURRENT: contextvars.ContextVar[Stop | None] = contextvars.ContextVar("payload_analysis_stop", default=None)


def current_stop() -> Stop | None:
    """The stop in force on this thread (None outside any ``stopping``)."""
    return _CURRENT.get()


def out_of_time() -> bool:
    """Raise Cancelled if this thread's analysis was cancelled; True once past its deadline."""
    stop = _CURRENT.get()
    return False if stop is None else stop.out_of_time()


def ran_out() -> bool:
    """Has this thread's analysis met its deadline (its results since are cut short)?"""
    stop = _CURRENT.get()
    return stop is not None and stop.ran_out


@contextmanager
def stopping(cancel: threading.Event | None = None, seconds: float = math.inf) -> Iterator[Stop]:
    """Within: out_of_time() follows ``cancel`` and a deadline ``seconds`` from now, and
    those of an enclosing ``stopping``."""
    if not seconds >= 0:
        raise ValueError(f"seconds: must be >= 0, got {seconds}")
    stop = Stop(cancel, time.monotonic() + seconds, outer=_CURRENT.get())
    token = _CURRENT.set(stop)
    try:
        yield stop
    finally:
        _CURRENT.reset(token)
