"""The progress of a tool's long work, on stderr (standard output keeps the tool's result).

On a terminal, a bar redrawn in place at most five times a second::

    load_diagram: [#########                     ]  31 % 203/651 points, 1 min 4 s left

elsewhere (a log, a pipe), one line per tenth of the work, so that a log keeps a few::

    load_diagram: 30 % (196/651 points), 1 min 6 s left

The time left is the time so far per unit of work times the units to go. A tool whose bar
is unfinished when it fails ends the line first (``open_line``, read by cli's one-line error).
"""

from __future__ import annotations

import sys
import time

open_line = [False]  # a bar's line on stderr is unfinished: end it before an error


def duration(seconds: float) -> str:
    """'45 s', '2 min 5 s', '1 h 3 min': a time to read at a glance."""
    seconds = max(0, round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60} min"


class Progress:
    """``progress(done, total)``: ``done`` of ``total`` units of work (``unit``: 'points')
    are done; shown as the module says, under ``label`` (the tool's name, or what it does)."""

    WIDTH = 30  # characters of the bar
    REDRAW = 0.2  # s between two drawings on a terminal

    def __init__(self, label: str, unit: str, stream=None, clock=time.monotonic):
        self.label, self.unit = label, unit
        self.stream = stream if stream is not None else sys.stderr
        try:
            self.terminal = self.stream.isatty()
        except (AttributeError, ValueError):  # no real stream (closed, a test's capture)
            self.terminal = False
        self.clock = clock
        self.start: float | None = None
        self.first = 0  # units done when the first call came (work done before is not timed)
        self.last = -1e9  # when the bar was last drawn
        self.tenths = -1  # tenths of the work shown as lines
        self.finished = False

    def __call__(self, done: int, total: int) -> None:
        if total <= 0 or self.finished:
            return
        now = self.clock()
        if self.start is None:
            self.start, self.first = now, done
        done = min(max(done, 0), total)
        finished = done >= total
        if self.terminal:
            if not finished and now - self.last < self.REDRAW:
                return
            self.last = now
            bar = "#" * int(self.WIDTH * done / total)
            text = (
                f"\r{self.label}: [{bar:<{self.WIDTH}}] {100 * done / total:3.0f} % "
                f"{done:,}/{total:,} {self.unit}, {self._time(done, total, now)}\x1b[K"
            )
            self._write(text + ("\n" if finished else ""), open_after=not finished)
        else:
            tenths = 10 * done // total
            if tenths <= self.tenths or (tenths == 0 and not finished):
                self.tenths = max(self.tenths, tenths)
                return
            self.tenths = tenths
            self._write(
                f"{self.label}: {10 * tenths} % ({done:,}/{total:,} {self.unit}), {self._time(done, total, now)}\n",
                open_after=False,
            )
        self.finished = finished

    def _time(self, done: int, total: int, now: float) -> str:
        elapsed = now - (self.start if self.start is not None else now)
        if done >= total:
            return f"done in {duration(elapsed)}"
        if done <= self.first:
            return "time left not known yet"
        return f"{duration(elapsed / (done - self.first) * (total - done))} left"

    def _write(self, text: str, open_after: bool) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):  # stderr closed: the work goes on without it
            return
        if self.stream is sys.stderr:
            open_line[0] = open_after
