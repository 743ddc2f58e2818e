"""Dual numbers: exact partial derivatives d/dq_k through any algorithm written on scalars."""

from __future__ import annotations


class Dual:
    """A scalar with its partial derivatives d/dq_k (forward-mode differentiation)."""

    __slots__ = ("value", "d")

    def __init__(self, value, d):
        self.value, self.d = value, d

    def __add__(self, other):
        if isinstance(other, Dual):
            return Dual(self.value + other.value, tuple(x + y for x, y in zip(self.d, other.d)))
        return Dual(self.value + other, self.d)

    __radd__ = __add__

    def __neg__(self):
        return Dual(-self.value, tuple(-x for x in self.d))

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if isinstance(other, Dual):
            return Dual(
                self.value * other.value,
                tuple(x * other.value + self.value * y for x, y in zip(self.d, other.d)),
            )
        return Dual(self.value * other, tuple(x * other for x in self.d))

    __rmul__ = __mul__


def _unit(n, k, value):
    return tuple(value if i == k else 0.0 for i in range(n))


def dual_angles(cs):
    """(cos, sin) pairs of the joint angles as dual numbers carrying d/dq_k (a prismatic
    joint's (d,) as (d,): d/dq_k d = 1)."""
    n = len(cs)
    return [
        (Dual(x[0], _unit(n, k, 1.0)),)
        if len(x) == 1
        else (Dual(x[0], _unit(n, k, -x[1])), Dual(x[1], _unit(n, k, x[0])))
        for k, x in enumerate(cs)
    ]


def partial(x, k):
    """d x / d q_k of a dual number (0 for a constant)."""
    return x.d[k] if isinstance(x, Dual) else 0.0
