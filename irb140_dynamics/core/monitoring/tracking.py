"""A controller's tracking, as a monitor keeps it: the errors it reports (q_ref - q), the
RMS per joint over the last seconds, and samples of reference and actual positions for a
plot, each error paired with the measured state it was computed from (by stamp).

A busy machine may drop that state before it is heard: the latest state stands in, which
shifts the plot by a sample while the error's RMS stays exact. Memory is bounded: the
states and errors kept are the newest; the plot's samples, one every ``step`` seconds.
"""

from __future__ import annotations

from collections import deque

import numpy as np

HISTORY_STEP = 0.01  # s between the samples kept for a plot


class TrackingLog:
    """``latest``: q of the newest state; ``recent``: (t [s], error) of the newest errors;
    ``history``: (t, q_ref, q) samples for a plot."""

    def __init__(self, step: float = HISTORY_STEP, states: int = 2000, errors: int = 5000):
        self.step = step
        self.latest: np.ndarray | None = None
        self.recent: deque[tuple[float, np.ndarray]] = deque(maxlen=errors)
        self.history: list[tuple[float, np.ndarray, np.ndarray]] = []
        self._positions: dict[int, np.ndarray] = {}  # stamp [ns] -> q, of the newest states
        self._stamps: deque[int] = deque(maxlen=states)

    def state(self, stamp: int, q) -> None:
        """A measured state: its positions [rad] at ``stamp`` [ns]."""
        if len(self._stamps) == self._stamps.maxlen:
            self._positions.pop(self._stamps[0], None)
        self._stamps.append(stamp)
        self._positions[stamp] = self.latest = np.array(q, dtype=float)

    def error(self, t: float, stamp: int, error) -> None:
        """The error q_ref - q [rad] reported at ``t`` [s] for the state of ``stamp`` [ns]."""
        error = np.array(error, dtype=float)
        self.recent.append((t, error))
        if self.history and t - self.history[-1][0] < self.step:
            return
        q = self._positions.get(stamp, self.latest)
        if q is not None and len(q) == len(error):
            self.history.append((t, q + error, q))

    def rms(self, t: float, window: float = 1.0) -> np.ndarray | None:
        """RMS of the errors reported in the ``window`` s before ``t``, per joint [rad]; None
        before any, or while no sample for a plot exists (no state heard yet)."""
        errors = [e for s, e in self.recent if s > t - window]
        if not errors or not self.history:
            return None
        return np.sqrt(np.mean(np.square(errors), axis=0))

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The plot's samples: t (N,) s, reference and actual positions (N, n) rad."""
        t, reference, actual = zip(*self.history)
        return np.array(t), np.array(reference), np.array(actual)
