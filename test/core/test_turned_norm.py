"""The norm bound of the load diagram's proof without the payload's direction as an angle:
the payload's own lever is m l at every pose (the physics it relies on), and the bound of
max over phi of |a + X cos(phi) + Y sin(phi)|^2 is above brute force on random sums."""

import math

import numpy as np
import pytest

from irb140_dynamics.core import irb140
from irb140_dynamics.core.payload import diagram
from irb140_dynamics.core.payload.family import PayloadFamily
from irb140_dynamics.core.payload.proof import certify
from irb140_dynamics.core.payload.proof.bounds import expand, sizes, sizes_of_s, turned_squared_max
from irb140_dynamics.core.payload.proof.harmonic import basis
from irb140_dynamics.core.payload.workspace import JointRanges

from ..support.common import random_model

PHI = np.linspace(-math.pi, math.pi, 361)


def largest_over_phi(a, X, Y, rows=1000):
    """max over phi of |a + X cos(phi) + Y sin(phi)| per row, (P, 3) each: (P,). The square
    is a quadratic form in (1, cos, sin) of the rows' dot products; ``rows`` at a time."""
    c, s = np.cos(PHI)[:, None], np.sin(PHI)[:, None]
    largest = []
    for first in range(0, len(a), rows):
        u, v, w = a[first : first + rows], X[first : first + rows], Y[first : first + rows]
        dot = [np.einsum("pk,pk->p", p, q) for p, q in ((u, u), (u, v), (u, w), (v, v), (v, w), (w, w))]
        squared = dot[0] + 2 * c * dot[1] + 2 * s * dot[2] + c * c * dot[3] + 2 * c * s * dot[4] + s * s * dot[5]
        largest.append(np.sqrt(np.maximum(squared.max(axis=0), 0.0)))
    return np.concatenate(largest)


@pytest.mark.parametrize("z, l", [(0.0, 0.1), (0.2, 0.15)])
def test_the_payloads_lever_is_m_l_at_every_pose(z, l):
    """|X cos(phi) + Y sin(phi)|, the part of omega_j the payload's offset turns, peaks at
    m l (kg m) over phi at every pose, as ``Objective.turn`` says, for every joint that is
    loaded by it; so the turn is an exact bound, not a guess."""
    model = irb140()
    _, shapes, _ = diagram._arm_of(model)
    family = shapes.family(z, l)
    m = 3.0
    forms = family.forms[0].affine(family.forms[1], m)
    rng = np.random.default_rng(7)
    for j in range(model.n - 1):
        norm, turn = family._norm(forms.omega[j], m, merge=False)
        theta = rng.uniform(-math.pi, math.pi, (200, len(norm.dims)))
        parts = basis(theta) @ norm.coefficients.T  # (P, 9): a, X, Y
        X, Y = parts[:, 3:6], parts[:, 6:9]
        lever = largest_over_phi(np.zeros_like(X), X, Y)
        assert turn >= lever.max()
        assert lever.max() == pytest.approx(m * l, rel=1e-6)


@pytest.mark.parametrize("seed", range(4))
def test_turned_squared_max_is_above_brute_force(seed):
    """On random sums a, X, Y over 3 joints and random boxes, with a turn bounding |X cos +
    Y sin| by the sums' sizes, the bound is above the largest |a + X cos + Y sin|^2 of
    dense poses and directions, and its value at the centre (radius 0) is too."""
    rng = np.random.default_rng(seed)
    d, boxes = 3, 6
    coefficients = rng.normal(size=(9, 3**d)) * np.where(rng.random(9) < 1 / 3, 1.0, 0.3)[:, None]
    turn = np.full(boxes, np.abs(coefficients[3:]).sum())  # >= |X| + |Y| everywhere
    centre = rng.uniform(-math.pi, math.pi, (boxes, d))
    radius = rng.uniform(0.0, 0.6, (boxes, d))
    N = expand(np.repeat(coefficients[None], boxes, axis=0).reshape(boxes * 9, -1), np.repeat(centre, 9, axis=0))
    size, bound, _ = turned_squared_max(
        N.reshape(boxes, 9, -1), sizes(radius), sizes_of_s(radius), radius, turn, np.zeros(boxes)
    )
    for k in range(boxes):
        theta = centre[k] + radius[k] * rng.uniform(-1.0, 1.0, (2000, d))
        parts = basis(theta) @ coefficients.T
        exact = largest_over_phi(parts[:, :3], parts[:, 3:6], parts[:, 6:9]).max() ** 2
        assert bound[k] >= exact
        at_centre = basis(centre[k : k + 1]) @ coefficients.T
        assert size[k] >= largest_over_phi(at_centre[:, :3], at_centre[:, 3:6], at_centre[:, 6:9])[0] * (1 - 1e-12)


@pytest.mark.parametrize("j", [1, 2, 3])
def test_turned_squared_max_holds_and_is_tight_on_an_arm(j):
    """On the IRB-140 carrying 3 kg at (0.1, 0, 0.1) m: over boxes about random poses, the
    bound is above |omega_j|^2 at dense poses and directions; about a pose, it comes within
    0.5 % of the largest value there as the box shrinks (the bound is exact at the centre
    where the offset turns fully outward; elsewhere, within (m l)^2 of it)."""
    model = irb140()
    _, shapes, _ = diagram._arm_of(model)
    family = shapes.family(0.1, 0.1)
    m = 3.0
    forms = family.forms[0].affine(family.forms[1], m)
    norm, turn = family._norm(forms.omega[j], m)
    d, rng = len(norm.dims), np.random.default_rng(j)
    poses = rng.uniform(-math.pi, math.pi, (20000, d))
    parts = basis(poses) @ norm.coefficients.T
    best = np.argsort(largest_over_phi(parts[:, :3], parts[:, 3:6], parts[:, 6:9]))[-4:]
    centre = np.vstack([poses[best], rng.uniform(-math.pi, math.pi, (4, d))])  # near the maxima, and anywhere
    for radius in (rng.uniform(0.05, 0.3, (8, d)), np.full((8, d), 0.01)):
        N = expand(np.repeat(norm.coefficients[None], 8, axis=0).reshape(8 * 9, -1), np.repeat(centre, 9, axis=0))
        _, bound, _ = turned_squared_max(
            N.reshape(8, 9, -1), sizes(radius), sizes_of_s(radius), radius, np.full(8, turn), np.zeros(8)
        )
        for k in range(8):
            theta = centre[k] + radius[k] * rng.uniform(-1.0, 1.0, (3000, d))
            parts = basis(theta) @ norm.coefficients.T
            largest = largest_over_phi(parts[:, :3], parts[:, 3:6], parts[:, 6:9]).max()
            assert bound[k] >= largest**2
            if radius[k, 0] == 0.01:
                assert math.sqrt(bound[k]) <= largest + (m * 0.1) ** 2 / largest + 0.005 * largest


@pytest.mark.parametrize("seed", [21, 22, 23, 24])
def test_proofs_with_the_turned_norm_are_above_brute_force_on_random_arms(seed, monkeypatch):
    """Random 5-joint arms, gravity in any direction, pivoted as the diagram does, a payload
    off the axis, the turned norm forced on every row, and a search that found 5 % of the
    largest torque less than it could (so the proof's own bounds must reach the maxima):
    every proven bound is at least the largest torque of 100,000 random poses and
    directions."""
    calls = []
    monkeypatch.setattr(certify, "turned_squared_max", lambda *a, **k: calls.append(1) or turned_squared_max(*a, **k))
    norm = PayloadFamily._norm
    monkeypatch.setattr(
        PayloadFamily, "_norm", lambda self, omega, m, merge=True, turned=True: norm(self, omega, m, merge)
    )
    rng = np.random.default_rng(seed)
    shapes = diagram._Shapes(diagram.pivoted(random_model(rng, 5)))
    family = shapes.family(float(rng.uniform(0, 0.3)), float(rng.uniform(0.05, 0.2)))
    ranges, mass = JointRanges.of(shapes.arm), float(rng.uniform(0.5, 5))
    values, poses = family.search(mass, ranges)
    scale = np.abs(values).max()
    rows = np.array([0, 1, 2, 3, 4, 6, 7, 8, 9, 10])
    extremes = family.extremes(mass, ranges, rows=rows, found=(values - 0.05 * scale, poses), share=0.5)
    Q = ranges.lower + rng.random((100_000, 6)) * (ranges.upper - ranges.lower)
    tau = family.static_torque(mass)(Q)
    dense = np.concatenate([tau.max(axis=0), (-tau).max(axis=0)])
    assert calls, "the turned norm was not used"
    assert np.all(extremes.bounds[rows] >= dense[rows] - 1e-12 * scale)
