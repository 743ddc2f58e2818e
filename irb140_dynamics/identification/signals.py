"""From raw samples to fit points: zero-phase filtering, differentiation and decimation.

Positions, velocities (when recorded) and efforts are smoothed, and velocities and
accelerations obtained, by Savitzky-Golay filters (a polynomial of degree ``POLYORDER``
fitted over a centred window; zero phase, exact for polynomials up to that degree). The
window follows the cut-off frequency f_c: its -3 dB point is at f_c by Schafer's rule
f_c / (f_s / 2) = (p + 1) / (3.2 M - 4.6), window 2 M + 1 samples. Without recorded
velocities, qd and qdd are the first and second derivatives of the positions; with them,
qd is the smoothed velocity and qdd its derivative. Efforts get the same smoothing as the
positions, so that torques and states keep the same (zero) delay and bandwidth.

The filtered signals carry nothing above f_c: they are kept at every ``stride``-th sample
only (about 4 f_c), which is what makes hour-long recordings cheap to fit.

Samples must be evenly spaced: a step more than 50 % off the recording's median step (a
gap, a repeated or out-of-order stamp), or a sample with a missing, non-finite or absurd
value (beyond ``LARGEST``: no arm's, and its square would overflow the sums), ends a segment; the first and last half window of every segment cannot be filtered and
are left out (counted in ``edge_samples``). Works chunk by chunk with a bounded buffer:
the results are those of filtering each segment whole.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy.linalg import lstsq

POLYORDER = 4
DEFAULT_CUTOFF = 10.0  # Hz
POINTS_PER_CUTOFF = 4.0  # fit points per second per Hz of cut-off
LARGEST = 1e6  # rad, rad/s, N m: a larger value (or NaN) makes its sample invalid
MAX_WINDOW = 100_001  # samples: 1 Hz cut-off at 60 kHz; longer is a unit mistake (time stamps, --cutoff)


@dataclass(frozen=True)
class FilterDesign:
    rate: float  # Hz, of the samples
    cutoff: float  # Hz
    window: int  # samples, odd
    stride: int  # samples between fit points

    @classmethod
    def of(cls, rate: float, cutoff: float = DEFAULT_CUTOFF) -> FilterDesign:
        if not cutoff > 0.0:
            raise ValueError(f"cutoff: must be > 0 Hz, got {cutoff}")
        nyquist_fraction = min(cutoff / (rate / 2.0), 1.0)
        half = math.ceil(((POLYORDER + 1) / nyquist_fraction + 4.6) / 3.2)
        half = max(half, POLYORDER // 2 + 1)
        if 2 * half + 1 > MAX_WINDOW:
            raise ValueError(
                f"a cut-off of {cutoff:g} Hz at {rate:.6g} samples/s needs a filter window of {2 * half + 1:,} "
                f"samples, more than {MAX_WINDOW:,}: raise --cutoff, or check that the time stamps are in seconds"
            )
        stride = max(1, int(rate / (POINTS_PER_CUTOFF * cutoff)))
        return cls(rate, cutoff, 2 * half + 1, stride)

    @property
    def half(self) -> int:
        return self.window // 2

    def coefficients(self, deriv: int) -> np.ndarray:
        """The centred window's weights for the ``deriv``-th derivative (as applied by a dot
        product): ``scipy.signal.savgol_coeffs(window, POLYORDER, deriv, 1 / rate, use="dot")``,
        computed as it does, without importing scipy.signal (0.8 s, most of identify's start)."""
        half = self.window // 2
        powers = np.arange(-half, half + 1, dtype=np.float64) ** np.arange(POLYORDER + 1.0)[:, None]
        y = np.zeros(POLYORDER + 1)
        y[deriv] = float(math.factorial(deriv)) / (1.0 / self.rate) ** deriv
        return lstsq(powers, y, cond=np.finfo(np.float64).eps * max(powers.shape))[0]

    def noise_correlation(self) -> float:
        """sum over m of rho(m * stride): how much the smoothing's correlation between fit
        points inflates a least-squares variance computed as if their noise were white."""
        h = self.coefficients(0)
        autocorrelation = np.correlate(h, h, mode="full")[len(h) - 1 :] / np.dot(h, h)
        return float(autocorrelation[0] + 2.0 * autocorrelation[self.stride :: self.stride].sum())


@dataclass(frozen=True, eq=False)
class FitPoints:
    index: np.ndarray  # (K,) sample index in the recording
    time: np.ndarray  # (K,) s
    q: np.ndarray  # (K, n)
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray

    def __len__(self) -> int:
        return len(self.index)

    def take(self, keep) -> FitPoints:
        return FitPoints(*(x[keep] for x in (self.index, self.time, self.q, self.qd, self.qdd, self.tau)))


class Differentiator:
    """Streams raw chunks (``recording.RawChunk``) to fit points (see the module's docstring)."""

    def __init__(self, design: FilterDesign, n: int, has_velocity: bool):
        self.design, self.n, self.has_velocity = design, n, has_velocity
        self.smooth, self.d1, self.d2 = (design.coefficients(d) for d in (0, 1, 2))
        self.step = 1.0 / design.rate
        self.edge_samples = 0  # left out: within half a window of a segment's ends
        self.invalid_samples = 0  # left out: a missing, non-finite or absurd value
        self._segment = None  # (index, time, values (B, channels)) of the open segment, trimmed
        self._length = 0  # samples in the open segment so far
        self._next = 0  # position in the buffer of the next fit point
        self._last = (-2, math.nan)  # (index, time) of the last valid sample

    def push(self, chunk) -> FitPoints | None:
        signals = [chunk.position, chunk.effort] + ([chunk.velocity] if self.has_velocity else [])
        values = np.hstack(signals)
        with np.errstate(invalid="ignore"):
            valid = (np.abs(values) <= LARGEST).all(axis=1) & np.isfinite(chunk.time)
        self.invalid_samples += int(np.sum(~valid))
        index = chunk.first + np.flatnonzero(valid)
        time, values = chunk.time[valid], values[valid]
        if len(index) == 0:
            return None
        previous_index = np.concatenate([[self._last[0]], index[:-1]])
        previous_time = np.concatenate([[self._last[1]], time[:-1]])
        regular = (index - previous_index == 1) & (np.abs(time - previous_time - self.step) <= 0.5 * self.step)
        regular[0] &= self._segment is not None
        self._last = (int(index[-1]), float(time[-1]))
        bounds = [*np.flatnonzero(~regular), len(index)]
        if bounds[0] != 0:
            bounds.insert(0, 0)
        outputs = []
        for a, b in zip(bounds[:-1], bounds[1:]):
            if not regular[a]:
                self._close()
            self._extend(index[a:b], time[a:b], values[a:b])
            outputs.append(self._emit())
        return joined([p for p in outputs if p is not None])

    def finish(self) -> None:
        """End of the recording: the open segment's last half window is left out."""
        self._close()

    def _extend(self, index, time, values):
        if self._segment is None:
            self._segment, self._next, self._length = (index, time, values), self.design.half, 0
        else:
            old = self._segment
            self._segment = (
                np.concatenate([old[0], index]),
                np.concatenate([old[1], time]),
                np.vstack([old[2], values]),
            )
        self._length += len(index)

    def _emit(self) -> FitPoints | None:
        index, time, values = self._segment
        half, stride, n = self.design.half, self.design.stride, self.n
        centres = np.arange(self._next, len(index) - half, stride)
        if len(centres) == 0:
            return None
        start = centres[0] - half  # the windows (K, channels, window): a strided view, no copy
        windows = sliding_window_view(values, self.design.window, axis=0)[start : centres[-1] - half + 1 : stride]
        position, effort = windows[:, :n], windows[:, n : 2 * n]
        if self.has_velocity:
            velocity = windows[:, 2 * n :]
            q, qd, qdd = position @ self.smooth, velocity @ self.smooth, velocity @ self.d1
        else:
            q, qd, qdd = position @ self.smooth, position @ self.d1, position @ self.d2
        points = FitPoints(index[centres], time[centres], q, qd, qdd, effort @ self.smooth)
        keep = centres[-1] + stride - half  # where the next fit point's window starts
        self._segment = (index[keep:], time[keep:], values[keep:])
        self._next = half
        return points

    def _close(self):
        if self._segment is not None:
            self.edge_samples += min(self._length, 2 * self.design.half)
        self._segment, self._length = None, 0


def joined(parts: list[FitPoints]) -> FitPoints | None:
    if not parts:
        return None
    if len(parts) == 1:
        return parts[0]
    return FitPoints(
        *(np.concatenate([getattr(p, f) for p in parts]) for f in ("index", "time", "q", "qd", "qdd", "tau"))
    )
