"""The parameter regressor: tau = Y(q, qd, qdd) pi, against rnea and Pinocchio's regressor."""

import numpy as np
import pinocchio as pin
import pytest

from irb140_dynamics.core import Friction, ModelError, RigidBody, irb140, rnea, rnea_batch
from irb140_dynamics.core.regressor import (
    INERTIAL_PARAMETERS,
    JOINT_PARAMETERS,
    JOINT_TERMS,
    LINK_PARAMETERS,
    PARAMETERS_PER_JOINT,
    inertial_parameters,
    parameter_names,
    regressor,
    regressor_batch,
    with_inertial_parameters,
)

from ..support import pinocchio_model
from ..support.common import assert_close, loaded_irb140, random_model, random_states, random_urdf_model

STATES = 50


def with_friction(model, rng):
    """The model with random friction and armature on every joint."""
    from dataclasses import replace

    joints = tuple(
        replace(j, friction=Friction(*rng.uniform(0.0, 3.0, 2)), armature=rng.uniform(0.0, 0.5)) for j in model.joints
    )
    return replace(model, joints=joints)


MODELS = {
    "irb140": irb140,
    "irb140_offset_payload_friction": lambda: with_friction(loaded_irb140(), np.random.default_rng(1)),
    **{
        f"dh_n{n}": (
            lambda n=n: with_friction(random_model(np.random.default_rng(30 + n), n), np.random.default_rng(n))
        )
        for n in (1, 2, 6, 7)
    },
    **{
        f"urdf_n{n}": (lambda n=n: random_urdf_model(np.random.default_rng(40 + n), n, friction=True))
        for n in (1, 3, 6)
    },
}


@pytest.fixture(scope="module", params=list(MODELS), ids=list(MODELS))
def case(request):
    model = MODELS[request.param]()
    return model, random_states(np.random.default_rng(5), model.n, STATES)


def test_regressor_times_parameters_is_rnea(case):
    model, (Q, QD, QDD) = case
    pi = inertial_parameters(model)
    assert pi.shape == (13 * model.n,)
    for q, qd, qdd in zip(Q, QD, QDD):
        Y = regressor(model, q, qd, qdd)
        assert Y.shape == (model.n, 13 * model.n)
        assert_close(Y @ pi, rnea(model, q, qd, qdd), rtol=1e-11, atol=1e-11, what="Y pi")


def test_batch_is_the_single_state_form(case):
    model, (Q, QD, QDD) = case
    Y = regressor_batch(model, Q, QD, QDD)
    assert Y.shape == (STATES, model.n, 13 * model.n)
    for k in range(STATES):
        np.testing.assert_allclose(Y[k], regressor(model, Q[k], QD[k], QDD[k]), rtol=1e-13, atol=1e-13)
    assert_close(Y @ inertial_parameters(model), rnea_batch(model, Q, QD, QDD), rtol=1e-11, atol=1e-11)


def test_rigid_body_columns_are_pinocchios_regressor(case):
    model, (Q, QD, QDD) = case
    pin_model = pinocchio_model.build(model)
    data = pin_model.createData()
    n = model.n
    for q, qd, qdd in zip(Q, QD, QDD):
        expected = np.reshape(pin.computeJointTorqueRegressor(pin_model, data, q, qd, qdd), (n, 10 * n))
        assert_close(regressor(model, q, qd, qdd)[:, : 10 * n], expected, rtol=1e-10, atol=1e-10, what="Y")


def test_rigid_body_parameters_are_pinocchios(case):
    """pi's link blocks are Pinocchio's dynamic parameters of its joints' inertias."""
    model, _ = case
    pin_model = pinocchio_model.build(model)
    expected = np.concatenate([pin_model.inertias[i + 1].toDynamicParameters() for i in range(model.n)])
    np.testing.assert_allclose(inertial_parameters(model)[: 10 * model.n], expected, rtol=1e-12, atol=1e-12)


def test_friction_and_armature_columns():
    model = with_friction(irb140(), np.random.default_rng(2))
    n, v_s = model.n, model.smoothing_velocity
    q, qd, qdd = np.full(n, 0.3), np.array([0.5, -0.2, 0.0, 0.004, -1.0, 3.0]), np.arange(1.0, n + 1.0)
    Y = regressor(model, q, qd, qdd)[:, 10 * n :]
    for i in range(n):
        expected = np.zeros(3 * n)
        expected[3 * i : 3 * i + 3] = qd[i], np.tanh(qd[i] / v_s), qdd[i]
        np.testing.assert_allclose(Y[i], expected, rtol=1e-15)


def test_parameter_names_follow_pis_order():
    model = irb140()
    names = parameter_names(model)
    assert len(names) == len(set(names)) == 13 * model.n
    assert names[:10] == [f"joint_1.{p}" for p in ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")]
    assert names[60:63] == ["joint_1.viscous", "joint_1.coulomb", "joint_1.armature"]
    assert names[-1] == "joint_6.armature"


@pytest.mark.parametrize("make", [loaded_irb140, lambda: random_urdf_model(np.random.default_rng(9), 5, friction=True)])
def test_parameters_round_trip(make):
    """with_inertial_parameters(model, pi) has pi again, and the same torques."""
    model = make()
    model = with_friction(model, np.random.default_rng(3))
    pi = inertial_parameters(model)
    rebuilt = with_inertial_parameters(model, pi)
    assert rebuilt.payload == RigidBody()
    np.testing.assert_allclose(inertial_parameters(rebuilt), pi, rtol=1e-12, atol=1e-12)
    Q, QD, QDD = random_states(np.random.default_rng(4), model.n, 20)
    assert_close(rnea_batch(rebuilt, Q, QD, QDD), rnea_batch(model, Q, QD, QDD), rtol=1e-12, atol=1e-12)
    other = pi.copy()
    other[: 10 * model.n] *= 1.5
    other[10 * model.n :] += 0.25
    assert_close(inertial_parameters(with_inertial_parameters(model, other)), other, rtol=1e-12, atol=1e-12)


def test_round_trip_of_a_massless_link():
    model = irb140()  # links 3 and 5 have no mass
    pi = inertial_parameters(model)
    assert np.all(pi[20:30] == 0.0)
    rebuilt = with_inertial_parameters(model, pi)
    assert rebuilt.joints[2].link == RigidBody()


@pytest.mark.parametrize(
    "change, field",
    [
        (lambda pi: pi.__setitem__(10, -1.0), "joint_2.link.mass"),  # negative mass
        (lambda pi: pi.__setitem__(slice(20, 24), [0.0, 0.1, 0.0, 0.0]), "joint_3.link.mass"),  # m c without mass
        (lambda pi: pi.__setitem__(4, -5.0), "joint_1.link.inertia"),  # Ixx < 0 about the CoM
        (lambda pi: pi.__setitem__(44, 1.0), "joint_5.link.inertia"),  # Ixx alone: triangle inequality
        (lambda pi: pi.__setitem__(60, -0.1), "joint_1.friction.viscous"),
        (lambda pi: pi.__setitem__(64, -0.1), "joint_2.friction.coulomb"),
        (lambda pi: pi.__setitem__(77, -0.1), "joint_6.armature"),
        (lambda pi: pi.__setitem__(0, np.nan), "joint_1.link.mass"),
    ],
)
def test_inconsistent_parameters_are_refused(change, field):
    model = irb140()
    pi = inertial_parameters(model)
    change(pi)
    with pytest.raises(ModelError) as error:
        with_inertial_parameters(model, pi)
    assert error.value.field == field, str(error.value)


def test_wrong_length_is_refused():
    with pytest.raises(ValueError, match="expected 78 parameters"):
        with_inertial_parameters(irb140(), np.zeros(77))


def test_the_layout_names_count_pi_and_its_columns():
    """pi: INERTIAL_PARAMETERS per link (Pinocchio's ten), then JOINT_TERMS per joint."""
    model = with_friction(irb140(), np.random.default_rng(3))
    n = model.n
    assert (INERTIAL_PARAMETERS, JOINT_TERMS, PARAMETERS_PER_JOINT) == (10, 3, 13)
    assert len(LINK_PARAMETERS) == INERTIAL_PARAMETERS and len(JOINT_PARAMETERS) == JOINT_TERMS
    names = parameter_names(model)
    pi = inertial_parameters(model)
    assert len(names) == pi.size == PARAMETERS_PER_JOINT * n
    assert names[INERTIAL_PARAMETERS * n] == f"{model.joints[0].name}.viscous"
    assert pi[INERTIAL_PARAMETERS * n + JOINT_TERMS * 2] == model.joints[2].friction.viscous
    assert regressor(model, np.zeros(n), np.zeros(n), np.zeros(n)).shape == (n, PARAMETERS_PER_JOINT * n)
