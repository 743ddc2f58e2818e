"""Joint friction and armature in the model and the dynamics."""

from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics.core import (
    Friction,
    ModelError,
    RobotModel,
    coriolis,
    coriolis_batch,
    derive_torque_limits,
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
from irb140_dynamics.core.model.friction import JointFriction

from ..support.common import assert_close, random_states, random_urdf_model

VISCOUS = np.array([4.0, 6.0, 3.0, 1.0, 0.8, 0.5])
COULOMB = np.array([8.0, 10.0, 6.0, 2.0, 1.5, 1.0])
ARMATURE = np.array([0.9, 1.2, 0.6, 0.15, 0.1, 0.05])


def with_friction(model: RobotModel, viscous=VISCOUS, coulomb=COULOMB, armature=ARMATURE) -> RobotModel:
    joints = tuple(
        replace(j, friction=Friction(v, c), armature=a) for j, v, c, a in zip(model.joints, viscous, coulomb, armature)
    )
    return replace(model, joints=joints)


@pytest.fixture(scope="module")
def states():
    return random_states(np.random.default_rng(11), 6, 40)


def test_friction_is_viscous_plus_smoothed_coulomb_in_rnea(states):
    plain, rough = irb140(), with_friction(irb140(), armature=np.zeros(6))
    v_s = rough.smoothing_velocity
    for q, qd, qdd in zip(*states):
        expected = rnea(plain, q, qd, qdd) + VISCOUS * qd + COULOMB * np.tanh(qd / v_s)
        np.testing.assert_allclose(rnea(rough, q, qd, qdd), expected, rtol=1e-13, atol=1e-12)
    assert_close(
        rnea_batch(rough, *states),
        rnea_batch(plain, *states) + JointFriction.of(rough).torques(states[1]),
        rtol=1e-13,
        atol=1e-12,
    )


def test_armature_is_on_the_mass_matrix_diagonal(states):
    plain, heavy = irb140(), with_friction(irb140())
    for q in states[0][:10]:
        np.testing.assert_allclose(
            mass_matrix(heavy, q), mass_matrix(plain, q) + np.diag(ARMATURE), rtol=1e-13, atol=1e-13
        )
    np.testing.assert_allclose(
        mass_matrix_batch(heavy, states[0]),
        mass_matrix_batch(plain, states[0]) + np.diag(ARMATURE),
        rtol=1e-13,
        atol=1e-13,
    )


def test_armature_in_rnea_is_its_torque(states):
    plain, heavy = irb140(), with_friction(irb140(), viscous=np.zeros(6), coulomb=np.zeros(6))
    for q, qd, qdd in zip(*states):
        np.testing.assert_allclose(
            rnea(heavy, q, qd, qdd), rnea(plain, q, qd, qdd) + ARMATURE * qdd, rtol=1e-13, atol=1e-12
        )


@pytest.mark.parametrize(
    "make", [lambda: with_friction(irb140()), lambda: random_urdf_model(np.random.default_rng(6), 6, friction=True)]
)
def test_forward_dynamics_inverts_rnea(make, states):
    """M(q) qdd + bias(q, qd) == tau with friction and armature in both."""
    model = make()
    Q, QD, _ = states
    TAU = np.random.default_rng(12).uniform(-80.0, 80.0, Q.shape)
    QDD = forward_dynamics_batch(model, Q, QD, TAU)
    for q, qd, tau, qdd in zip(Q, QD, TAU, QDD):
        np.testing.assert_allclose(forward_dynamics(model, q, qd, tau), qdd, rtol=1e-11, atol=1e-11)
        bias = rnea(model, q, qd, np.zeros(6))
        np.testing.assert_allclose(mass_matrix(model, q) @ qdd + bias, tau, rtol=1e-11, atol=1e-10)
        np.testing.assert_allclose(rnea(model, q, qd, qdd), tau, rtol=1e-11, atol=1e-10)


def test_friction_slows_a_free_arm_down():
    """No torque, no gravity: M qdd = -(C qd + friction), friction on the spinning joint only."""
    model = with_friction(irb140().with_gravity([0.0, 0.0, 0.0]))
    q, qd = np.zeros(6), np.array([2.0, 0, 0, 0, 0, 0])
    qdd = forward_dynamics(model, q, qd, np.zeros(6))
    drag = VISCOUS[0] * 2.0 + COULOMB[0] * np.tanh(2.0 / model.smoothing_velocity)
    expected = np.linalg.solve(mass_matrix(model, q), -drag * np.eye(6)[0] - coriolis(model, q, qd))
    np.testing.assert_allclose(qdd, expected, rtol=1e-12, atol=1e-12)
    assert qdd[0] < 0


def test_gravity_coriolis_and_static_payload_analysis_leave_friction_out(states):
    plain, rough = irb140(), with_friction(irb140())
    Q, QD, _ = states
    np.testing.assert_array_equal(gravity_batch(rough, Q), gravity_batch(plain, Q))
    np.testing.assert_array_equal(coriolis_batch(rough, Q, QD), coriolis_batch(plain, Q, QD))
    np.testing.assert_array_equal(gravity(rough, Q[0]), gravity(plain, Q[0]))
    np.testing.assert_array_equal(coriolis(rough, Q[0], QD[0]), coriolis(plain, Q[0], QD[0]))
    assert derive_torque_limits(rough).values == derive_torque_limits(plain).values


def test_smooth_coulomb_is_continuous_odd_and_zero_at_rest():
    friction = JointFriction(np.zeros(1), np.array([10.0]), 0.01)
    v = np.linspace(-0.2, 0.2, 40001)[:, None]
    tau = friction.torques(v)[:, 0]
    assert friction.torques(np.zeros((1, 1)))[0, 0] == 0.0
    np.testing.assert_allclose(friction.torques(-v), -friction.torques(v), rtol=0, atol=0)
    assert np.max(np.abs(np.diff(tau))) < 10.0 * 1e-5 / 0.01 * 1.0001  # slope at most coulomb / v_s
    assert np.all(np.diff(tau) >= 0) and np.all(np.diff(tau)[np.abs(v[1:, 0]) < 0.1] > 0)  # monotonic: no chatter
    assert friction.torques(np.array([[0.01]]))[0, 0] == pytest.approx(10.0 * np.tanh(1.0))
    assert friction.torques(np.array([[0.03]]))[0, 0] > 0.99 * 10.0


def test_smoothing_velocity_is_a_model_parameter():
    slow = RobotModel.from_params(with_friction(irb140()).to_params() | {"friction.smoothing_velocity": 0.1})
    qd = np.full(6, 0.05)
    q = np.full(6, 0.2)
    rigid = gravity(slow, q) + coriolis(slow, q, qd)
    np.testing.assert_allclose(
        rnea(slow, q, qd, np.zeros(6)) - rigid, VISCOUS * qd + COULOMB * np.tanh(0.5), rtol=1e-9, atol=1e-9
    )


def test_defaults_are_zero_and_no_friction_object():
    model = irb140()
    assert model.friction is None
    assert all(j.friction == Friction() and j.armature == 0.0 for j in model.joints)
    assert model.smoothing_velocity == 0.01


def test_parameters_round_trip_with_friction():
    model = replace(with_friction(irb140()), smoothing_velocity=0.02)
    params = model.to_params()
    assert params["joint_2.friction.viscous"] == VISCOUS[1]
    assert params["joint_3.friction.coulomb"] == COULOMB[2]
    assert params["joint_6.armature"] == ARMATURE[5]
    assert params["friction.smoothing_velocity"] == 0.02
    assert RobotModel.from_params(params) == model
    urdf = random_urdf_model(np.random.default_rng(8), 4, friction=True)
    assert RobotModel.from_params(urdf.to_params()) == urdf


@pytest.mark.parametrize(
    "field", ["friction.viscous", "friction.coulomb", "armature", "velocity_limit", "acceleration_limit"]
)
def test_negative_values_are_refused(field):
    params = irb140().to_params() | {f"joint_4.{field}": -0.5}
    with pytest.raises(ModelError) as error:
        RobotModel.from_params(params)
    assert error.value.field == f"joint_4.{field}" and "must be >= 0" in str(error.value)


@pytest.mark.parametrize("value", [0.0, -0.01, float("nan")])
def test_smoothing_velocity_must_be_positive(value):
    with pytest.raises(ModelError) as error:
        RobotModel.from_params(irb140().to_params() | {"friction.smoothing_velocity": value})
    assert error.value.field == "friction.smoothing_velocity"


def test_non_finite_friction_is_refused():
    with pytest.raises(ModelError, match="^joint_1.friction.coulomb: "):
        RobotModel.from_params(irb140().to_params() | {"joint_1.friction.coulomb": float("inf")})
