"""Base parameters and excitation trajectories."""

import math
import re

import numpy as np
import pytest

from irb140_dynamics.core import irb140
from irb140_dynamics.core.regressor import parameter_names, regressor_batch
from irb140_dynamics.identification.base import find_base_parameters, random_states
from irb140_dynamics.identification.excitation import (
    FourierTrajectory,
    Limits,
    check_limits,
    condition_number,
    optimise_excitation,
    shaped,
)

from ..support.common import random_model, random_urdf_model


@pytest.fixture(scope="module")
def irb140_base():
    return find_base_parameters(irb140())


def test_irb140_has_52_base_parameters(irb140_base):
    """36 of the links (the classical count of this structure), joints 3-6's armature (1 and 2's
    merge with Izz), every joint's two friction parameters; 11 parameters do nothing."""
    base = irb140_base
    assert base.count == 52
    labels = base.labels()
    assert sum(label.endswith(("viscous", "coulomb")) for label in labels) == 12
    assert [label for label in labels if label.endswith("armature")] == [f"joint_{i}.armature" for i in (3, 4, 5, 6)]
    assert sum(not label.endswith(("viscous", "coulomb", "armature")) for label in labels) == 36
    assert [base.names[i] for i in base.unidentifiable] == [
        *(f"joint_1.{p}" for p in ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz")),
        "joint_2.m",
        "joint_2.mcz",
    ]


def test_irb140_listing_reads_as_the_regrouping_rules(irb140_base):
    lines = irb140_base.describe(4)
    assert lines[0] == (
        "b1   = joint_1.Izz + joint_2.Iyy + 0.1296 joint_3.m + joint_3.Iyy + 0.1296 joint_4.m "
        "+ 0.1296 joint_5.m + 0.1296 joint_6.m + joint_1.armature"
    )  # 0.1296 = a_2^2
    assert "b2   = joint_2.mcx + 0.36 joint_3.m + 0.36 joint_4.m + 0.36 joint_5.m + 0.36 joint_6.m" in lines
    names = set(parameter_names(irb140()))
    for line in lines:  # every term is a named parameter with an optional coefficient
        _, combination = line.split(" = ")
        for term in re.split(r" [+-] ", combination):
            assert term.split(" ")[-1] in names, line


@pytest.mark.parametrize(
    "make",
    [
        lambda: irb140(),
        lambda: random_model(np.random.default_rng(3), 5),
        lambda: random_urdf_model(np.random.default_rng(4), 6, friction=True),
    ],
    ids=["irb140", "dh_n5", "urdf_n6"],
)
def test_base_regressor_gives_the_same_torques(make):
    """Y pi == Y_b beta on states the base parameters were not found with, for any pi."""
    model = make()
    base = find_base_parameters(model, seed=1)
    rng = np.random.default_rng(2)
    Y = regressor_batch(model, *random_states(model, 60, rng))
    for _ in range(3):
        pi = rng.normal(size=13 * model.n)
        np.testing.assert_allclose(base.columns(Y) @ base.of(pi), Y @ pi, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(base.of(pi), base.matrix() @ pi, rtol=1e-12, atol=1e-12)
    flat = Y.reshape(-1, Y.shape[-1])
    assert base.count == np.linalg.matrix_rank(flat, tol=1e-8 * np.abs(flat).max())
    assert np.abs(Y[..., base.unidentifiable]).max(initial=0.0) <= 1e-12 * np.abs(Y).max()  # rounding only


def trajectory(seed=0, n=6, harmonics=4, period=5.0):
    free = np.random.default_rng(seed).normal(size=2 * n * (harmonics - 1))
    return shaped(free, n, harmonics, period, Limits.of(irb140()))


def test_fourier_derivatives_are_consistent():
    traj = trajectory()
    t = np.linspace(0.0, 5.0, 201)
    h = 1e-5
    Q, QD, QDD = traj.evaluate(t)
    Qp, QDp, _ = traj.evaluate(t + h)
    Qm, QDm, _ = traj.evaluate(t - h)
    np.testing.assert_allclose((Qp - Qm) / (2 * h), QD, atol=1e-7)
    np.testing.assert_allclose((QDp - QDm) / (2 * h), QDD, atol=1e-6)


def test_trajectory_starts_at_rest_and_repeats():
    traj = trajectory(1)
    Q, QD, QDD = traj.evaluate([0.0, traj.period, 2 * traj.period])
    np.testing.assert_allclose(QD, 0.0, atol=1e-12)
    np.testing.assert_allclose(QDD, 0.0, atol=1e-12)
    np.testing.assert_allclose(Q[1], Q[0], atol=1e-12)
    np.testing.assert_allclose(Q[2], Q[0], atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_trajectory_uses_and_keeps_within_the_limits(seed):
    model = irb140()
    traj = trajectory(seed)
    for rate in (7.0, 100.0, 1000.0):
        assert check_limits(model, traj, rate) == []
    Q, QD, QDD = traj.evaluate(np.linspace(0.0, traj.period, 20001))
    limits = Limits.of(model)  # within the 5 % margin (up to the peaks between the check points)
    slack = 2e-4 * (limits.upper - limits.lower)
    assert np.all(limits.lower - slack <= Q) and np.all(limits.upper + slack >= Q)
    # each joint is as large as a limit allows: one of its three measures is within 1 % of it
    use = np.max(
        [
            (Q.max(0) - Q.min(0)) / (limits.upper - limits.lower),
            np.abs(QD).max(0) / limits.speed,
            np.abs(QDD).max(0) / limits.acceleration,
        ],
        axis=0,
    )
    assert np.all(use > 0.97) and np.all(use <= 1.0002), use


def test_a_joint_without_limits_gets_defaults():
    from dataclasses import replace

    model = irb140()
    joints = list(model.joints)
    joints[0] = replace(joints[0], velocity_limit=0.0, acceleration_limit=0.0)
    limits = Limits.of(replace(model, joints=tuple(joints)))
    assert limits.speed[0] == 1.0 and limits.acceleration[0] == 5.0


@pytest.mark.slow
def test_optimisation_lowers_the_condition_number(irb140_base):
    model = irb140()
    result = optimise_excitation(model, period=4.0, harmonics=3, seed=5, iterations=3, base=irb140_base)
    assert result.condition_number < result.start_condition_number
    assert result.condition_number == pytest.approx(
        condition_number(model, irb140_base, result.trajectory, 100), rel=0.5
    )
    assert check_limits(model, result.trajectory, 50.0) == []
    assert math.isfinite(result.condition_number)


def test_excitation_refuses_bad_settings():
    with pytest.raises(ValueError, match="harmonics"):
        optimise_excitation(irb140(), harmonics=1)
    with pytest.raises(ValueError, match="period"):
        optimise_excitation(irb140(), period=0.0)


def test_still_trajectory_is_singular(irb140_base):
    still = FourierTrajectory(5.0, np.zeros(6), np.zeros((6, 3)), np.zeros((6, 3)))
    assert condition_number(irb140(), irb140_base, still, 50) == math.inf
