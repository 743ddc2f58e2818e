"""Identities the equations of motion must satisfy, and batch forms equal to single states."""

import numpy as np
import pytest

from irb140_dynamics.core import (
    coriolis,
    coriolis_batch,
    coriolis_matrix,
    flange_jacobian,
    flange_pose,
    forward_dynamics,
    forward_dynamics_batch,
    gravity,
    gravity_batch,
    irb140,
    mass_matrix,
    mass_matrix_batch,
    rnea,
    rnea_batch,
)

from ..support.common import assert_close, model_makers, random_states

MODELS = model_makers(seed=200, sizes=(3, 7))


@pytest.fixture(scope="module", params=list(MODELS), ids=list(MODELS))
def robot(request):
    return MODELS[request.param]()


@pytest.fixture
def states(robot):
    return random_states(np.random.default_rng(11), robot.n, 100)


def test_mass_matrix_symmetric_positive_definite(robot, states):
    for q in states[0]:
        M = mass_matrix(robot, q)
        np.testing.assert_array_equal(M, M.T)
        assert np.linalg.eigvalsh(M)[0] > 1e-9 * np.linalg.norm(M)


def test_mdot_minus_2c_is_skew_and_c_qd_is_coriolis(robot, states):
    h = 1e-5
    for q, qd, _ in zip(*states):
        Mdot = (mass_matrix(robot, q + h * qd) - mass_matrix(robot, q - h * qd)) / (2 * h)
        C = coriolis_matrix(robot, q, qd)
        S = Mdot - 2 * C
        assert_close(S + S.T, np.zeros_like(S), 0.0, 1e-6 * (np.linalg.norm(Mdot) + 2 * np.linalg.norm(C)), "Mdot - 2C")
        assert_close(C @ qd, coriolis(robot, q, qd), 1e-12, 1e-14, "C qd")


def test_rnea_is_m_qdd_plus_c_qd_plus_g(robot, states):
    for q, qd, qdd in zip(*states):
        terms = (mass_matrix(robot, q) @ qdd, coriolis(robot, q, qd), gravity(robot, q))
        scale = sum(np.linalg.norm(t) for t in terms)
        assert_close(rnea(robot, q, qd, qdd), sum(terms), 0.0, 1e-12 * scale, "tau")


def test_power_balance_along_a_smooth_trajectory(robot):
    """qd . (tau - g) = dT/dt, T = qd^T M qd / 2, on q(t) a sum of sines."""
    rng = np.random.default_rng(5)
    amplitude, omega, phase = (
        rng.uniform(0.2, 1.0, (3, robot.n)),
        rng.uniform(0.5, 3.0, (3, robot.n)),
        rng.uniform(0, 2 * np.pi, (3, robot.n)),
    )

    def trajectory(t):
        angle = omega * t + phase
        q = (amplitude * np.sin(angle)).sum(axis=0)
        qd = (amplitude * omega * np.cos(angle)).sum(axis=0)
        qdd = (-amplitude * omega**2 * np.sin(angle)).sum(axis=0)
        return q, qd, qdd

    def kinetic_energy(t):
        q, qd, _ = trajectory(t)
        return 0.5 * qd @ mass_matrix(robot, q) @ qd

    h = 1e-5
    for t in np.linspace(0.0, 5.0, 51):
        q, qd, qdd = trajectory(t)
        power = qd @ (rnea(robot, q, qd, qdd) - gravity(robot, q))
        dT_dt = (kinetic_energy(t + h) - kinetic_energy(t - h)) / (2 * h)
        scale = np.abs(qd) @ (np.abs(mass_matrix(robot, q) @ qdd) + np.abs(coriolis(robot, q, qd)))
        assert abs(power - dT_dt) <= 1e-6 * scale, f"t={t}: power {power} != dT/dt {dT_dt}"


def test_flange_wrench_acts_through_the_jacobian_transpose(robot, states):
    """rnea(..., f_ext) - rnea(...) = -J^T (f, n), the wrench rotated from flange to base frame."""
    rng = np.random.default_rng(3)
    for q, qd, qdd in zip(*states):
        wrench = rng.normal(0.0, 20.0, 6)
        R = flange_pose(robot, q)[:3, :3]
        in_base = np.concatenate([R @ wrench[:3], R @ wrench[3:]])
        expected = -flange_jacobian(robot, q).T @ in_base
        actual = rnea(robot, q, qd, qdd, wrench) - rnea(robot, q, qd, qdd)
        assert_close(actual, expected, 1e-9, 1e-9, "wrench torques")


def test_batch_forms_equal_single_states(robot):
    Q, QD, QDD = random_states(np.random.default_rng(17), robot.n, 500)
    TAU = rnea_batch(robot, Q, QD, QDD) + np.random.default_rng(18).normal(0.0, 10.0, Q.shape)
    batches = {
        "rnea": (rnea_batch(robot, Q, QD, QDD), [rnea(robot, *s) for s in zip(Q, QD, QDD)]),
        "gravity": (gravity_batch(robot, Q), [gravity(robot, q) for q in Q]),
        "mass_matrix": (mass_matrix_batch(robot, Q), [mass_matrix(robot, q) for q in Q]),
        "coriolis": (coriolis_batch(robot, Q, QD), [coriolis(robot, *s) for s in zip(Q, QD)]),
        "forward_dynamics": (
            forward_dynamics_batch(robot, Q, QD, TAU),
            [forward_dynamics(robot, *s) for s in zip(Q, QD, TAU)],
        ),
    }
    for name, (batch, singles) in batches.items():
        assert batch.shape == (len(Q),) + singles[0].shape, name
        for k, single in enumerate(singles):
            assert_close(batch[k], single, 1e-12, 1e-14, f"{name} state {k}")


# -- arguments: one bad value is an error naming the argument, never a plausible torque -------------

NAN, INF = float("nan"), float("inf")


@pytest.mark.parametrize("bad", [NAN, INF, -INF])
def test_a_non_finite_state_value_is_refused(bad):
    model = irb140()
    good, wrong = [0.1] * 6, [bad, 0.0, 0.0, 0.0, 0.0, 0.0]  # nan * 0 would fold away in gravity
    calls = {
        "q": [
            lambda x: gravity(model, x),
            lambda x: mass_matrix(model, x),
            lambda x: rnea(model, x, good, good),
            lambda x: coriolis(model, np.array(x), good),
            lambda x: coriolis_matrix(model, x, good),
        ],
        "qd": [lambda x: rnea(model, good, x, good), lambda x: coriolis(model, good, x)],
        "qdd": [lambda x: rnea(model, good, good, np.array(x))],
        "f_ext": [lambda x: rnea(model, good, good, good, x)],
        "tau": [lambda x: forward_dynamics(model, good, good, x)],
    }
    for name, functions in calls.items():
        for function in functions:
            with pytest.raises(ValueError, match=f"^{name}: must be finite"):
                function(wrong)


def test_huge_finite_values_are_not_mistaken_for_non_finite():
    """The quick check sums the values; a sum that overflows is checked value by value: the
    input passes, and it is the result that is refused, as not finite."""
    with pytest.raises(ValueError, match=r"^rnea: the result is not finite for q=\[0\.0, .*qdd=\[1e\+308, 1e\+308"):
        rnea(irb140(), [0.0] * 6, [0.0] * 6, [1e308, 1e308, 0.0, 0.0, 0.0, 0.0])


def test_a_non_finite_batch_value_is_refused():
    model = irb140()
    Q = np.zeros((50, 6))
    bad = Q.copy()
    bad[17, 0] = np.nan
    with pytest.raises(ValueError, match=r"^Q: must be finite \(state 17"):
        gravity_batch(model, bad)
    with pytest.raises(ValueError, match="^QDD: must be finite"):
        rnea_batch(model, Q, Q, bad)
    with pytest.raises(ValueError, match="^TAU: must be finite"):
        forward_dynamics_batch(model, Q, Q, np.where(np.isnan(bad), np.inf, 0.0))


def test_batch_arguments_of_different_lengths_are_refused():
    model = irb140()
    Q = np.zeros((100, 6))
    with pytest.raises(ValueError, match="^QD: expected 100 states like Q, got 99$"):
        rnea_batch(model, Q, Q[:99], Q)
    with pytest.raises(ValueError, match="^QDD: expected 100 states like Q, got 1$"):
        rnea_batch(model, Q, Q, Q[:1])  # would broadcast
    with pytest.raises(ValueError, match="^QD: expected 100 states like Q, got 101$"):
        coriolis_batch(model, Q, np.zeros((101, 6)))
    with pytest.raises(ValueError, match="^TAU: expected 100 states like Q, got 1$"):
        forward_dynamics_batch(model, Q, Q, Q[:1])
