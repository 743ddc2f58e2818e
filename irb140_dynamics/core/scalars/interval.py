"""Interval numbers: rigorous enclosures of real values through floating-point arithmetic.

An Interval holds lower and upper bounds ``lo`` <= ``hi`` (floats or NumPy arrays: many
intervals at once). Each + - * rounds outward (np.nextafter, one ulp each way), so the
exact real result of the same operations on any values within the operands lies within
the computed interval. Exact cases stay exact: a product with the constant 0 is 0, with
+-1 the operand; a float constant is an exact point. cos and sin enclose the range of
the function over the interval (rounded outward by a few ulps).

The algorithms (``algorithms.rnea`` and the others) use only + - * on their scalars and
take (cos, sin) pairs, so they run on Intervals unchanged: that is how the static torques
get rigorous bounds (see ``harmonic`` and ``certify``).
"""

from __future__ import annotations

import math

import numpy as np

_DOWN, _UP = -np.inf, np.inf
_TRIG_SLACK = 4 * np.finfo(float).eps  # relative widening of a computed cos or sin
_TINY = 1e-300


class Interval:
    """[lo, hi], elementwise; see the module docstring."""

    __slots__ = ("lo", "hi")
    __array_priority__ = 1000  # ndarray * Interval goes to Interval.__rmul__

    def __init__(self, lo, hi=None):
        self.lo = lo
        self.hi = lo if hi is None else hi

    @property
    def mid(self):
        return 0.5 * (self.lo + self.hi)

    @property
    def rad(self):
        """A radius r with [lo, hi] within mid +- r (rounded up)."""
        mid = self.mid
        return np.nextafter(np.maximum(self.hi - mid, mid - self.lo), _UP)

    def __repr__(self) -> str:
        return f"Interval({self.lo!r}, {self.hi!r})"

    def __neg__(self) -> Interval:
        return Interval(-self.hi, -self.lo)

    def __add__(self, other):
        if isinstance(other, Interval):
            lo, hi = self.lo + other.lo, self.hi + other.hi
        elif _is_zero(other):
            return self
        else:
            lo, hi = self.lo + other, self.hi + other
        return _outward(lo, hi)

    __radd__ = __add__

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if isinstance(other, Interval):
            if self.lo is self.hi and other.lo is other.hi:  # two points: one product
                product = self.lo * other.lo
                return _outward(product, product)
            if other.lo is other.hi or self.lo is self.hi:  # a point: two products
                point, wide = (other, self) if other.lo is other.hi else (self, other)
                a, b = wide.lo * point.lo, wide.hi * point.lo
                if _fresh(a, b):
                    lo = np.minimum(a, b)
                    return _outward(lo, np.maximum(a, b, out=a))
                return _outward(np.minimum(a, b), np.maximum(a, b))
            p0, p1, p2, p3 = self.lo * other.lo, self.lo * other.hi, self.hi * other.lo, self.hi * other.hi
            if _fresh(p0, p1, p2, p3):  # (the same values, fewer arrays made)
                lo = np.minimum(p0, p1)
                hi = np.maximum(p0, p1, out=p0)
                np.minimum(lo, np.minimum(p2, p3, out=p1), out=lo)
                np.maximum(hi, np.maximum(p2, p3, out=p2), out=hi)
                return _outward(lo, hi)
            lo = np.minimum(np.minimum(p0, p1), np.minimum(p2, p3))
            hi = np.maximum(np.maximum(p0, p1), np.maximum(p2, p3))
        elif np.ndim(other) == 0:
            if other == 0:
                return 0.0
            if other == 1:
                return self
            if other == -1:
                return -self
            lo, hi = (self.lo * other, self.hi * other) if other > 0 else (self.hi * other, self.lo * other)
        else:
            a, b = self.lo * other, self.hi * other
            lo, hi = np.minimum(a, b), np.maximum(a, b)
        return _outward(lo, hi)

    __rmul__ = __mul__

    def cos(self) -> Interval:
        """An enclosure of cos over [lo, hi]."""
        return _trig(np.cos, self.lo, self.hi, 0.0)

    def sin(self) -> Interval:
        """An enclosure of sin over [lo, hi] (cos shifted by pi/2)."""
        return _trig(np.sin, self.lo, self.hi, math.pi / 2)


def _outward(lo, hi) -> Interval:
    """[lo, hi] widened by an ulp each way; lo and hi are the caller's own (changed in place
    where float arrays; the same array for both is taken as a point)."""
    if isinstance(lo, np.ndarray) and isinstance(hi, np.ndarray) and lo.dtype == hi.dtype == np.float64:
        if lo is hi:
            hi = lo.copy()
        return Interval(_step(lo, -1), _step(hi, 1))
    return Interval(np.nextafter(lo, _DOWN), np.nextafter(hi, _UP))


def _step(x: np.ndarray, direction: int) -> np.ndarray:
    """x (float64, changed in place) one ulp up (direction 1) or down (-1): np.nextafter
    toward +-inf, bit for bit, at a fraction of its cost. A finite nonzero double's
    neighbour is its bit pattern as an integer plus or minus one (by its sign); zeros,
    infinities and nans are left to np.nextafter."""
    bits = x.view(np.int64)
    special = ~np.isfinite(x)
    special |= x == 0
    held = x[special] if special.any() else None
    away = bits >> 63  # -1 where negative, else 0: | 1 gives the step of a bit pattern away from 0
    away |= 1
    if direction > 0:
        bits += away
    else:
        bits -= away
    if held is not None:
        x[special] = np.nextafter(held, direction * np.inf)
    return x


def _fresh(*arrays) -> bool:
    """Are these arrays of one shape and type (results of products: the caller's own)?"""
    first = arrays[0]
    return isinstance(first, np.ndarray) and all(
        isinstance(a, np.ndarray) and a.shape == first.shape and a.dtype == np.float64 for a in arrays
    )


def _is_zero(x) -> bool:
    return np.ndim(x) == 0 and x == 0


def _trig(fn, lo, hi, peak):
    """The range of fn (cos or sin) over [lo, hi]: the ends, and +1 / -1 where the
    interval holds a peak (peak + 2 k pi) or trough (peak + pi + 2 k pi)."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    a, b = fn(lo), fn(hi)
    low, high = np.minimum(a, b), np.maximum(a, b)
    turns = 2 * math.pi
    has_peak = np.floor((hi - peak) / turns) >= np.ceil((lo - peak) / turns)
    has_trough = np.floor((hi - peak - math.pi) / turns) >= np.ceil((lo - peak - math.pi) / turns)
    whole = hi - lo >= turns
    high = np.where(has_peak | whole, 1.0, high + _TRIG_SLACK * np.abs(high) + _TINY)
    low = np.where(has_trough | whole, -1.0, low - _TRIG_SLACK * np.abs(low) - _TINY)
    return Interval(np.maximum(low, -1.0), np.minimum(high, 1.0))


def bounds_of(x, shape) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) arrays of ``shape`` for an Interval or a plain number (an exact point)."""
    if isinstance(x, Interval):
        return np.broadcast_to(x.lo, shape), np.broadcast_to(x.hi, shape)
    value = np.broadcast_to(np.asarray(x, dtype=float), shape)
    return value, value
