"""Fewer nonzero inertial parameters, the same joint torques: regrouping (Khalil and
Kleinfinger's base parameters, 1987).

A revolute joint turns link i about its axis b, through its joint origin o'_i. Part of the
link's inertia neither changes under that turn nor resists it:

- its mass m, as a point mass at o'_i (on the axis),
- its first moment along the axis, (b . h') b about o'_i,
- an inertia lam (1 - b b^T) about o'_i (no moment about b itself).

That part moves exactly as if it were fixed to the parent link, so it can be added to the
parent's inertia (in the parent's frame, about its origin) or, on the base, dropped. Every
joint torque stays the same at every q, qd, qdd: tau, M, C, g, the momenta and their
derivatives do not see the move; the wrenches inside the links do (no kernel outputs one).
Link i can be left with m = 0, no first moment along b, and, when b is a coordinate axis,
one moment of inertia 0 (lam chosen so): its wrench in rnea takes fewer operations. The
regrouped links are no bodies (zero masses, inertias that are not positive): only joint
torques may be computed from them.

Moving the mass can add products of inertia to the parent (a joint origin off two of the
parent's axes), which costs more than it saves; so each link, from the tips to the base,
moves the parts that leave it and its parent with the fewest operations (``_operations``;
of equal ones, the choice moving most: what a parent holds, it may move on). A prismatic
link keeps its parameters (its children still move theirs into it).

Once the choices are made, regrouping is linear in the links' inertial parameters: the
payload's link, whose inertia the kernels take as an input, is regrouped as the others
(``affine``), its moved parts reaching its parent and, through it, the links below.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from itertools import product

import numpy as np

from irb140_dynamics.core.algorithms.topology import parents
from irb140_dynamics.core.model.rigid_body import inertia_entries, inertia_matrix, shift_inertia

_PRODUCTS = ((0, 1), (0, 2), (1, 2))  # the products of inertia's entries
MOMENTS = range(4, 7)  # the moments of inertia's places among a link's m, h, I (10 numbers)
# a link's m, h, I with no zero and no two moments of inertia equal
GENERIC = (1.3, 0.07, 0.11, 0.13, 0.5, 0.7, 0.9, 0.017, 0.019, 0.023)


def regrouped(links, choices: tuple | None = None) -> tuple:
    """``links`` (see ``recursions.Link``, a tree or a chain) with the same joint torques
    and fewer nonzero inertial parameters (see the module); ``choices``: what each link
    moves (``choices_of``), None to choose for these links."""
    return _regrouped(links, choices)[0]


def choices_of(links) -> tuple:
    """What ``regrouped`` moves from each link: an index into its choices (None: a prismatic
    link, which moves nothing)."""
    return _regrouped(links, None)[1]


def _regrouped(links, choices) -> tuple[tuple, tuple]:
    links, parent = list(links), parents(links)
    chosen = [None] * len(links)
    added = [None] * len(links)  # (m, h, I) moved into each link by its children
    for i in reversed(range(len(links))):
        link = links[i]
        own = _with(_parameters(link), added[i])
        if link.prismatic:
            links[i] = _replaced(link, own)
            continue
        options = _choices(link, own, None if choices is None else choices[i])
        if choices is not None:
            chosen[i] = choices[i]
        elif parent[i] < 0:  # onto the base: dropped
            chosen[i] = _cheapest(options, lambda rest, moved: _operations(*rest))
        else:
            above = _with(_parameters(links[parent[i]]), added[parent[i]])  # the parent's, so far
            chosen[i] = _cheapest(
                options, lambda rest, moved, above=above: _operations(*rest) + _operations(*_with(above, moved))
            )
        rest, moved = options[chosen[i]]
        if parent[i] >= 0:
            added[parent[i]] = _with(added[parent[i]], moved)
        links[i] = _replaced(link, rest)
    return tuple(links), tuple(chosen)


def _cheapest(options: dict, cost) -> int:
    """The index of the option (rest, moved) of least ``cost``; of equal ones the last: the
    options run from moving nothing to moving the mass, the first moment along b and a
    moment of inertia (``_choices``), and what a parent holds, it may move on."""
    return min(reversed(options), key=lambda j: cost(*options[j]))


def _choices(link, own, only: int | None = None) -> dict:
    """{index: (rest, moved)} for each choice of what link i moves (the choice ``only``
    alone, when given), in this order: its mass or not, then its first moment along b or
    not, then lam 0 or the one that zeroes a moment of inertia across b (b a coordinate
    axis; the first across, then the second). rest: (m, h, I) about o_i, in frame i; moved:
    about o_{i-1}, in the parent's frame."""
    m, h, inertia = own
    b, p = np.array(link.b), np.array(link.p)
    across = np.eye(3) - np.outer(b, b)
    axis = [k for k in range(3) if abs(b[k]) == 1.0]
    _, h_joint, inertia_joint = _shifted(m, h, inertia, p)  # about o'_i
    R = _matrix_of(link.R0) @ _matrix_of(link.R1)  # frame i -> the parent's (any turn: the part is unchanged)
    p0 = np.zeros(3) if link.p0 is None else np.array(link.p0)
    zeroings = [None] + ([(axis[0] + 1) % 3, (axis[0] + 2) % 3] if axis else [])
    options = {}
    for pair, (move_mass, move_along) in enumerate(product((False, True), repeat=2)):
        indices = range(pair * len(zeroings), (pair + 1) * len(zeroings))
        if only is not None and only not in indices:
            continue
        m_moved = m if move_mass else 0.0
        h_moved = (b @ h_joint) * b if move_along else np.zeros(3)
        m_rest, h_rest, inertia_rest = _shifted(m - m_moved, h_joint - h_moved, inertia_joint, -p)  # about o_i
        if move_mass and move_along and axis:  # kept, the mass's moment -m (b . p) stays there
            h_rest[axis[0]] = 0.0
        for index, zeroed in zip(indices, zeroings):
            if only is not None and index != only:
                continue
            lam = 0.0 if zeroed is None else inertia_rest[zeroed, zeroed]
            rest_inertia = inertia_rest - lam * across
            if zeroed is not None:
                rest_inertia[zeroed, zeroed] = 0.0
            moved = _shifted(m_moved, R @ h_moved, R @ (lam * across) @ R.T, p0)
            options[index] = (m_rest, h_rest, rest_inertia), moved
    return options


def _operations(m, h, inertia) -> int:
    """About how many operations a link's wrench (rnea's force and moment) takes for its
    nonzero parameters: m a (6), each h_k (10: its sweep and h x a); with products of
    inertia, each moment of inertia 4 and each product 8 (I dw and I w) and w x (I w) 9;
    without, each moment 2 (I dw) and each nonzero difference of two moments 2 (w x (I w) is
    ((Izz - Iyy) w_y w_z, ...), see ``vectors.gyroscopic``)."""
    products = sum(inertia[j, k] != 0.0 for j, k in _PRODUCTS)
    moments = sum(inertia[k, k] != 0.0 for k in range(3))
    cost = 6 * (m != 0.0) + 10 * int(np.count_nonzero(h))
    if products:
        return cost + 4 * moments + 8 * products + 9
    return cost + 2 * moments + 2 * sum(inertia[j, j] != inertia[k, k] for j, k in _PRODUCTS)


def _shifted(m, h, inertia, r):
    """(m, h, I) about O - r (``shift_inertia``), as arrays."""
    m, h, six = shift_inertia(m, tuple(h), inertia_entries(inertia), tuple(r))
    return m, np.array(h), inertia_matrix(six)


def _parameters(link):
    """A link's (m, h, I), as arrays."""
    return link.m, np.array(link.h, dtype=float), inertia_matrix([float(x) for x in link.I])


def _with(a, b):
    """The sum of two (m, h, I); None adds nothing."""
    if a is None or b is None:
        return b if a is None else a
    return a[0] + b[0], a[1] + b[1], a[2] + b[2]


def _replaced(link, parameters):
    """The link with the (m, h, I) of arrays as its floats."""
    m, h, inertia = parameters
    return replace(link, m=float(m), h=tuple(float(x) for x in h), I=inertia_entries(inertia))


def _matrix_of(R) -> np.ndarray:
    """A Link's rotation (None: identity) as an array."""
    return np.eye(3) if R is None else np.array(R, dtype=float)


@dataclass(frozen=True)
class Affine:
    """Links regrouped with one link's inertia x (its m, h, I: 10 numbers) left free: each
    number x reaches is ``base``'s plus ``rows[e]`` . x, at ``entries[e]`` (the link's index,
    the number's place among its m, h, I); ``base`` has x = 0."""

    base: tuple
    entries: tuple[tuple[int, int], ...]
    rows: tuple[tuple[float, ...], ...]

    def values(self, x) -> tuple[float, ...]:
        """The entries' numbers (floats) for the inertia x: each sum of the rounded products
        correctly rounded (math.fsum), so that a difference of equal moments of inertia (their
        coefficients +-1) is 0."""
        return tuple(
            math.fsum((numbers_of(self.base[i])[j], *(c * v for c, v in zip(row, x))))
            for (i, j), row in zip(self.entries, self.rows)
        )

    def links(self, values) -> tuple:
        """``base`` with the entries' numbers (floats, or a kernel's inputs) put in."""
        numbers = {i: list(numbers_of(self.base[i])) for i, _ in self.entries}
        for (i, j), value in zip(self.entries, values):
            numbers[i][j] = value
        return tuple(with_numbers(link, numbers[i]) if i in numbers else link for i, link in enumerate(self.base))


def affine(links, at: int, like=GENERIC) -> Affine:
    """The regrouping of ``links`` with link ``at``'s inertia left free (see Affine), by the
    choices made for ``like`` there (10 numbers: its zeros and equal moments of inertia
    decide them). Linear in that inertia: each column is the regrouping of the unit inertia
    alone (the other links' inertias 0), by the same choices."""
    choices = choices_of(tuple(with_numbers(link, like) if i == at else link for i, link in enumerate(links)))
    zero = (0.0,) * 10
    base = regrouped(tuple(with_numbers(link, zero) if i == at else link for i, link in enumerate(links)), choices)
    columns = []
    for j in range(10):
        unit = tuple(float(k == j) for k in range(10))
        alone = tuple(with_numbers(link, unit if i == at else zero) for i, link in enumerate(links))
        columns.append([numbers_of(link) for link in regrouped(alone, choices)])
    entries = tuple((i, j) for i in range(len(links)) for j in range(10) if any(c[i][j] != 0.0 for c in columns))
    rows = tuple(tuple(column[i][j] for column in columns) for i, j in entries)
    return Affine(base, entries, rows)


def numbers_of(link) -> tuple:
    """A link's m, h, I as 10 numbers."""
    return (link.m, *link.h, *link.I)


def with_numbers(link, x):
    """The link with its m, h, I from 10 numbers."""
    return replace(link, m=x[0], h=tuple(x[1:4]), I=tuple(x[4:10]))


def pattern_of(x) -> tuple[float, ...]:
    """A link's inertia x (10 numbers) as the choices see it: GENERIC where x is not 0,
    equal moments of inertia kept equal; inertias that differ only in their numbers, not in
    these, regroup by the same choices."""
    like = [0.0 if v == 0.0 else g for v, g in zip(x, GENERIC)]
    for j in MOMENTS:
        same = [e for e in MOMENTS if e < j and x[e] == x[j] != 0.0]
        if same:
            like[j] = like[same[0]]
    return tuple(like)
