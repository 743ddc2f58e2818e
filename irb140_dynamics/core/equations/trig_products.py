"""The trigonometric series of ``trig_series`` written as one would by hand: polynomials in
the sines and cosines of the joint angles, with the angles of joints turning about parallel
axes summed (the IRB-140's c23 = cos(q2 + q3)).

The angles phi_j are chosen per quantity: phi_j = q_g + ... + q_j over a run of joints
g..j, or q_j alone. A run is extended to the next joint where that makes the series'
frequencies smaller (parallel axes make q_i + q_(i+1) appear together). Each term
c exp(i k.phi) is then multiplied out as prod (cos phi_j + i sin phi_j)^k_j, squares of
sines are replaced by 1 - cos^2 (so the form is unique), and equal monomials combine.
"""

from __future__ import annotations

from collections import defaultdict
from math import comb

from . import trig_series as ts


def angle_runs(entries_by_quantity: list[list], n: int) -> list[tuple[int, int]]:
    """The runs (first, last) of joints, 0-based, whose summed angles make the shortest series."""
    keys = [key[2] for entries in entries_by_quantity for x in entries if isinstance(x, ts.Series) for key in x.terms]
    runs: list[tuple[int, int]] = []
    for j in range(n):
        if runs and _cost(keys, runs[:-1] + [(runs[-1][0], j)], n) < _cost(keys, runs + [(j, j)], n):
            runs[-1] = (runs[-1][0], j)
        else:
            runs.append((j, j))
    return runs


def _cost(keys, runs, n) -> int:
    partial = runs + [(j, j) for j in range(runs[-1][1] + 1, n)]
    return sum(sum(map(abs, _in_angles(k, partial))) for k in keys)


def _in_angles(k, runs) -> tuple[int, ...]:
    """k.q as k'.phi: within a run phi_j = phi_(j-1) + q_j, so k'_j = k_j - k_(j+1)."""
    out = []
    for first, last in runs:
        for j in range(first, last + 1):
            out.append(k[j] - (k[j + 1] if j < last else 0))
    return tuple(out)


def products(x, runs, tolerance: float) -> dict[tuple, dict[tuple, float]]:
    """{velocities: {monomial: coefficient}}; a monomial is ((cos power, sin power) per angle phi_j)."""
    n = len(runs)
    if not isinstance(x, ts.Series):
        return {(): {((0, 0),) * n: float(x)}} if abs(x) > tolerance else {}
    out: dict[tuple, dict] = defaultdict(lambda: defaultdict(float))
    for (p, v, k), c in x.terms.items():
        if p >= 0:
            raise ValueError("the product form is for numeric parameters")
        for monomial, value in _expanded(c, _in_angles(k, runs)).items():
            out[v][monomial] += value
    return {
        v: {m: c for m, c in sorted(poly.items(), key=_reading_order) if abs(c) > tolerance}
        for v, poly in sorted(out.items(), key=lambda item: (len(item[0]), item[0]))
    }


def _reading_order(item) -> tuple:
    """Lower degree first, then the angles in joint order, cosines before sines."""
    monomial, _ = item
    degree = sum(a + b for a, b in monomial)
    return (degree, tuple((j, -a, b) for j, (a, b) in enumerate(monomial) if a or b))


def _expanded(c: complex, k) -> dict[tuple, float]:
    """Re(c prod_j (cos phi_j + i sin phi_j)^k_j) as {monomial: coefficient}, sin^2 = 1 - cos^2.
    (A term and its conjugate are both in the series: the sum of their real parts is the value.)"""
    poly = {(): c}
    for kj in k:
        power, sign = abs(kj), (1 if kj >= 0 else -1)
        factor = {(power - r, r): comb(power, r) * (1j * sign) ** r for r in range(power + 1)}
        poly = {m + (slot,): v * w for m, v in poly.items() for slot, w in factor.items()}
    real: dict[tuple, float] = defaultdict(float)
    for monomial, value in poly.items():
        for reduced, sign in _without_sine_squares(monomial):
            real[reduced] += sign * value.real
    return real


def _without_sine_squares(monomial):
    """The monomial with every sin^2 replaced by 1 - cos^2: [(monomial, sign)]."""
    results = [((), 1)]
    for cos_power, sin_power in monomial:
        pairs = sin_power // 2  # (1 - cos^2)^pairs = sum_r C(pairs, r) (-cos^2)^r
        slots = [((cos_power + 2 * r, sin_power % 2), comb(pairs, r) * (-1) ** r) for r in range(pairs + 1)]
        results = [(m + (slot,), s * w) for m, s in results for slot, w in slots]
    return results


def angle_sums(runs) -> list[tuple[int, ...]]:
    """For each angle phi_j, the joints (0-based) it sums."""
    return [tuple(range(first, j + 1)) for first, last in runs for j in range(first, last + 1)]


def value(form: dict, runs, q, velocities) -> float:
    """A product form (see ``products``) at angles q and velocities (qd then qdd)."""
    import math

    phi = [sum(q[i] for i in joints) for joints in angle_sums(runs)]
    total = 0.0
    for v, poly in form.items():
        factor = math.prod(velocities[j] for j in v)
        for monomial, c in poly.items():
            total += factor * c * math.prod(math.cos(p) ** a * math.sin(p) ** b for p, (a, b) in zip(phi, monomial))
    return total
