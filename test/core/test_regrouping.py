"""Regrouped inertial parameters (``algorithms.regrouping``): the same joint torques and mass
matrix from fewer nonzero parameters, on chains, trees and sliding joints."""

from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics.core import irb140
from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.algorithms import regrouping
from irb140_dynamics.core.algorithms.regrouping import affine, regrouped, with_numbers
from irb140_dynamics.core.algorithms.topology import parents
from irb140_dynamics.core.urdf import load_urdf

from ..support.common import OFFSET_PAYLOAD, random_model, random_urdf_model
from ..support.two_arms import TWO_ARMS
from .test_derivatives import THREE_BRANCHES

MODELS = {
    "irb140": lambda: irb140(payload=OFFSET_PAYLOAD),
    "dh_n7": lambda: random_model(np.random.default_rng(71), 7),
    "urdf_n7": lambda: random_urdf_model(np.random.default_rng(72), 7),
    "tree_with_a_slide": lambda: load_urdf(THREE_BRANCHES).model,
    "two_arms": lambda: load_urdf(TWO_ARMS).model,
}


def joint_inputs(rng, links):
    """Each link's (cos, sin), or its slide (d,), at random: every link on its own (a mimic
    joint's link too: regrouping holds for any motion of each joint)."""
    out = []
    for link in links:
        if link.prismatic:
            out.append((rng.uniform(-0.5, 0.5),))
        else:
            t = rng.uniform(-np.pi, np.pi)
            out.append((np.cos(t), np.sin(t)))
    return out


def nonzero(links) -> int:
    return sum(x != 0.0 for link in links for x in (link.m, *link.h, *link.I))


@pytest.mark.parametrize("name", list(MODELS))
def test_the_same_torques_and_mass_matrix_from_fewer_parameters(name):
    model = MODELS[name]()
    links = algorithms.chain(model)
    fewer = regrouped(links)
    assert nonzero(fewer) < nonzero(links)
    rng = np.random.default_rng(5)
    n = len(links)
    for _ in range(20):
        cs = joint_inputs(rng, links)
        qd, qdd, wrench = rng.uniform(-2, 2, n), rng.uniform(-5, 5, n), rng.normal(0, 20, 6)
        tau = algorithms.rnea(links, cs, qd, qdd, model.gravity, wrench[:3], wrench[3:], at=model.carrier)
        same = algorithms.rnea(fewer, cs, qd, qdd, model.gravity, wrench[:3], wrench[3:], at=model.carrier)
        np.testing.assert_allclose(same, tau, rtol=0, atol=1e-12 * np.abs(tau).max())
        M = np.array(algorithms.crba(links, cs))
        np.testing.assert_allclose(algorithms.crba(fewer, cs), M, rtol=0, atol=1e-13 * np.abs(M).max())


def test_a_turning_link_leaves_its_mass_its_axial_moment_and_a_moment_of_inertia_to_its_parent():
    """Links turning about z with full inertias: each keeps m = 0, h_z = 0 and I_xx or
    I_yy = 0 (the root's go to the base, the others' to a parent whose every parameter is
    nonzero already)."""
    links = algorithms.chain(random_urdf_model(np.random.default_rng(9), 7))
    about_z = tuple(replace(link, u=(0.0, 0.0, 1.0), b=(0.0, 0.0, 1.0), R0=None, R1=None) for link in links)
    for link in regrouped(about_z):
        assert link.m == 0.0 and link.h[2] == 0.0 and 0.0 in link.I[:2]


@pytest.mark.parametrize("name", list(MODELS))
def test_the_payloads_link_regroups_linearly_for_any_inertia(name):
    """``affine``: the numbers the payload's link's inertia reaches, for inertias other than
    the one its choices were made for (with zeros, symmetric, or none), give the torques and
    M of the links with that inertia; the links' other numbers do not change with it."""
    model = MODELS[name]()
    links, at = algorithms.chain(model), model.carrier
    regrouping = affine(links, at)
    rng = np.random.default_rng(8)
    n = len(links)
    inertias = [rng.normal(0.0, 1.0, 10) for _ in range(3)]
    inertias += [np.array([2.0, 0.0, 0.0, 0.3, 0.1, 0.1, 0.2, 0.0, 0.0, 0.0]), np.zeros(10)]
    for x in inertias:
        x = tuple(float(v) for v in x)
        fewer = regrouping.links(regrouping.values(x))
        assert {i for i, _ in regrouping.entries} >= {at}
        assert all(fewer[i] == regrouping.base[i] for i in range(n) if i not in {i for i, _ in regrouping.entries})
        with_x = tuple(with_numbers(link, x) if i == at else link for i, link in enumerate(links))
        for _ in range(3):
            cs = joint_inputs(rng, links)
            qd, qdd = rng.uniform(-2, 2, n), rng.uniform(-5, 5, n)
            tau = algorithms.rnea(with_x, cs, qd, qdd, model.gravity)
            same = algorithms.rnea(fewer, cs, qd, qdd, model.gravity)
            np.testing.assert_allclose(same, tau, rtol=0, atol=1e-12 * np.abs(tau).max())
            M = np.array(algorithms.crba(with_x, cs))
            np.testing.assert_allclose(algorithms.crba(fewer, cs), M, rtol=0, atol=1e-13 * np.abs(M).max())


@pytest.mark.parametrize("name", ["irb140", "dh_n7", "urdf_n7", "tree_with_a_slide"])
def test_every_choice_of_what_a_link_moves_keeps_the_torques(name):
    """Each of a link's choices (its mass or not, its first moment along the axis or not, a
    moment of inertia or not), not only the one taken: the DH rows' joint origins off
    their links' origins (p . b = d) are where a kept mass leaves a first moment along the
    axis."""
    model = MODELS[name]()
    links, parent = algorithms.chain(model), parents(algorithms.chain(model))
    rng = np.random.default_rng(6)
    n = len(links)
    states = [(joint_inputs(rng, links), rng.uniform(-2, 2, n), rng.uniform(-5, 5, n)) for _ in range(3)]
    expected = [algorithms.rnea(links, cs, qd, qdd, model.gravity) for cs, qd, qdd in states]
    for i, link in enumerate(links):
        if link.prismatic:
            continue
        for rest, moved in regrouping._choices(link, regrouping._parameters(link)).values():
            changed = list(links)
            changed[i] = regrouping._replaced(link, rest)
            if parent[i] >= 0:
                above = regrouping._with(regrouping._parameters(links[parent[i]]), moved)
                changed[parent[i]] = regrouping._replaced(links[parent[i]], above)
            for (cs, qd, qdd), tau in zip(states, expected):
                same = algorithms.rnea(changed, cs, qd, qdd, model.gravity)
                np.testing.assert_allclose(same, tau, rtol=0, atol=1e-12 * np.abs(tau).max())
