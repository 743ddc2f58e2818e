"""Which fit points a recording's identification uses: rest trimmed at both ends, and the
held-out points chosen among those that move.

A torque row is used when its joint is fast enough for the Coulomb model (``rows_used``);
a fit point *moves* when at least one of its rows is used. A recording usually holds rest
before and after the motion (`record` started before the motion, stopped after it): the
points before the first moving point and after the last are trimmed. Of the moving points
that remain, the last ``held_out`` fraction (counted in moving points, not in samples or
seconds) is held out for validation, the rest fitted: so the held-out part always moves,
however much rest the recording holds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def rows_used(qd: np.ndarray, qdd: np.ndarray, min_speed: float, half_window: float) -> np.ndarray:
    """(K, n) which torque rows are used: |qd| >= min_speed anywhere in the filter window,
    judged by |qd| >= min_speed + |qdd| half_window (``half_window`` in s)."""
    return np.abs(qd) >= min_speed + np.abs(qdd) * half_window


@dataclass(frozen=True)
class Selection:
    """Indices into a recording's fit points: [first, split) fitted, [split, end) held out."""

    first: int  # the first moving point
    split: int  # the first held-out point (== end: nothing held out)
    end: int  # one past the last moving point
    moving: int  # moving points within [first, end)
    held_moving: int  # of them held out

    @property
    def train(self) -> slice:
        return slice(self.first, self.split)

    @property
    def held(self) -> slice:
        return slice(self.split, self.end)


def select(moves: np.ndarray, held_out: float = 0.0) -> Selection | None:
    """Trim the rest at both ends of ``moves`` (K,) and hold out the last ``held_out``
    fraction of the moving points (at least one, and at least one left to fit; 1: all of
    them); None when nothing moves."""
    index = np.flatnonzero(moves)
    if len(index) == 0:
        return None
    first, end, count = int(index[0]), int(index[-1]) + 1, len(index)
    if held_out <= 0.0:
        return Selection(first, end, end, count, 0)
    if held_out >= 1.0:  # a validation recording: all of it
        return Selection(first, first, end, count, count)
    held = min(max(math.ceil(held_out * count - 1e-9), 1), count - 1)
    if held <= 0:
        return Selection(first, end, end, count, 0)
    split = int(index[count - held])
    return Selection(first, split, end, count, held)
