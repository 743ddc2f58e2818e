"""The equations as trigonometric series, for reading (see ``trig_products`` and ``latex``).

A ``Series`` is a scalar for the core's recursions (``+ - *`` with numbers and each other):
a finite sum of terms

    coefficient * parameter * (product of qd_j, qdd_j) * exp(i k . q)

kept as a dict {(parameter, velocities, k): complex coefficient}. Running ``rnea`` or
``crba`` on Series gives each quantity expanded, with the products of sines and cosines
turned into sines and cosines of sums of angles (c2 c3 - s2 s3 = cos(q2 + q3)): exact,
canonical, so equal terms always combine. ``parameter`` is -1 or the index of a symbolic
parameter (the recursions are linear in them, so one per term is enough).
"""

from __future__ import annotations

import cmath
from collections import defaultdict

RELATIVE_ROUNDOFF = 1e-15  # terms below this fraction of a series' largest are round-off


class Series:
    __slots__ = ("terms",)

    def __init__(self, terms: dict):
        self.terms = terms

    # -- arithmetic ------------------------------------------------------------------

    def __add__(self, other):
        if isinstance(other, Series):
            terms = dict(self.terms)
            for key, c in other.terms.items():
                terms[key] = terms.get(key, 0.0) + c
            return _pruned(terms)
        if other == 0:
            return self
        return self + constant(other, self)

    __radd__ = __add__

    def __neg__(self):
        return Series({key: -c for key, c in self.terms.items()})

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if not isinstance(other, Series):
            if other == 0:
                return 0.0
            return Series({key: c * other for key, c in self.terms.items()})
        terms = defaultdict(complex)
        for (p1, v1, k1), c1 in self.terms.items():
            for (p2, v2, k2), c2 in other.terms.items():
                if p1 >= 0 and p2 >= 0:
                    raise ValueError("a product of two parameters: the recursion is not linear in them")
                key = (max(p1, p2), tuple(sorted(v1 + v2)), tuple(a + b for a, b in zip(k1, k2)))
                terms[key] += c1 * c2
        return _pruned(terms)

    __rmul__ = __mul__

    # -- reading -----------------------------------------------------------------------

    def value(self, q, velocities, parameters=()) -> float:
        """The series at angles q, velocities (qd then qdd, one list) and parameter values."""
        total = 0.0
        for (p, v, k), c in self.terms.items():
            phase = sum(kj * qj for kj, qj in zip(k, q))
            term = c * cmath.exp(1j * phase)
            for j in v:
                term *= velocities[j]
            total += term * (parameters[p] if p >= 0 else 1.0)
        return total.real


def _pruned(terms: dict):
    if not terms:
        return 0.0
    largest = max(abs(c) for c in terms.values())
    cut = RELATIVE_ROUNDOFF * largest
    kept = {key: c for key, c in terms.items() if abs(c) > cut}
    return Series(kept) if kept else 0.0


def constant(x, like: Series) -> Series:
    n = len(next(iter(like.terms))[2])
    return Series({(-1, (), (0,) * n): complex(x)})


def angle(i: int, n: int, offset: float) -> tuple[Series, Series]:
    """(cos, sin) of q_i + offset."""
    up = tuple(1 if j == i else 0 for j in range(n))
    down = tuple(-x for x in up)
    e = cmath.exp(1j * offset)
    cos = Series({(-1, (), up): e / 2, (-1, (), down): e.conjugate() / 2})
    sin = Series({(-1, (), up): e / 2j, (-1, (), down): -e.conjugate() / 2j})
    return cos, sin


def variable(j: int, n: int) -> Series:
    """The velocity variable j (qd_j for j < n, qdd_(j-n) after)."""
    return Series({(-1, (j,), (0,) * n): 1.0 + 0j})


def parameter(p: int, n: int) -> Series:
    return Series({(p, (), (0,) * n): 1.0 + 0j})
