"""The core against Pinocchio, built independently from the same joints and inertials:
DH rows, and joints in URDF form (any origin, any axis, a flange placement, armature)."""

import numpy as np
import pinocchio as pin
import pytest

from irb140_dynamics.core import (
    coriolis,
    coriolis_matrix,
    forward_dynamics,
    gravity,
    irb140,
    mass_matrix,
    rnea,
)

from ..support import pinocchio_model
from ..support.common import assert_close, loaded_irb140, random_model, random_states, random_urdf_model

STATES = 200
RTOL = 1e-9
ATOL = 1e-12  # N m (or rad/s^2): only matters where the reference is itself ~0

MODELS = {
    "irb140": irb140,
    "irb140_offset_payload": loaded_irb140,
    **{f"random_n{n}": (lambda n=n: random_model(np.random.default_rng(100 + n), n)) for n in range(1, 8)},
    **{f"urdf_form_n{n}": (lambda n=n: random_urdf_model(np.random.default_rng(200 + n), n)) for n in (1, 3, 6, 7)},
}


class Case:
    """A robot, its Pinocchio twin and seeded random states."""

    def __init__(self, robot, seed):
        self.robot = robot
        self.pin_model = pinocchio_model.build(robot)
        self.data = self.pin_model.createData()
        rng = np.random.default_rng(seed)
        self.Q, self.QD, self.QDD = random_states(rng, robot.n, STATES)
        self.TAU = rng.uniform(-100.0, 100.0, (STATES, robot.n))
        self.WRENCH = np.hstack([rng.normal(0.0, 50.0, (STATES, 3)), rng.normal(0.0, 10.0, (STATES, 3))])

    def states(self):
        return zip(self.Q, self.QD, self.QDD, self.TAU, self.WRENCH)


@pytest.fixture(scope="module", params=list(MODELS), ids=list(MODELS))
def case(request):
    return Case(MODELS[request.param](), seed=7)


def test_pinocchio_model_has_one_revolute_joint_per_dh_row(case):
    assert case.pin_model.nq == case.pin_model.nv == case.robot.n
    total_mass = sum(j.link.mass for j in case.robot.joints) + case.robot.payload.mass
    assert sum(inertia.mass for inertia in case.pin_model.inertias) == pytest.approx(total_mass, rel=1e-14)


def test_rnea(case):
    for q, qd, qdd, _, _ in case.states():
        expected = pin.rnea(case.pin_model, case.data, q, qd, qdd)
        assert_close(rnea(case.robot, q, qd, qdd), expected, RTOL, ATOL, f"tau at q={q}")


def test_gravity(case):
    for q, _, _, _, _ in case.states():
        expected = pin.computeGeneralizedGravity(case.pin_model, case.data, q)
        assert_close(gravity(case.robot, q), expected, RTOL, ATOL, f"g at q={q}")


def test_mass_matrix(case):
    for q, _, _, _, _ in case.states():
        upper = np.triu(pin.crba(case.pin_model, case.data, q))
        expected = upper + np.triu(upper, 1).T
        assert_close(mass_matrix(case.robot, q), expected, RTOL, ATOL, f"M at q={q}")


def test_coriolis(case):
    for q, qd, _, _, _ in case.states():
        nle = pin.nonLinearEffects(case.pin_model, case.data, q, qd)
        expected = nle - pin.computeGeneralizedGravity(case.pin_model, case.data, q)
        assert_close(coriolis(case.robot, q, qd), expected, RTOL, ATOL, f"C qd at q={q} qd={qd}")


def test_coriolis_matrix(case):
    for q, qd, _, _, _ in case.states():
        expected = pin.computeCoriolisMatrix(case.pin_model, case.data, q, qd)
        assert_close(coriolis_matrix(case.robot, q, qd), expected, RTOL, ATOL, f"C at q={q} qd={qd}")


def test_forward_dynamics(case):
    for q, qd, _, tau, _ in case.states():
        expected = pin.aba(case.pin_model, case.data, q, qd, tau)
        assert_close(forward_dynamics(case.robot, q, qd, tau), expected, RTOL, ATOL, f"qdd at q={q}")


def test_rnea_with_flange_wrench(case):
    for q, qd, qdd, _, wrench in case.states():
        fext = pinocchio_model.flange_fext(case.pin_model, case.robot, wrench)
        expected = pin.rnea(case.pin_model, case.data, q, qd, qdd, fext)
        assert_close(rnea(case.robot, q, qd, qdd, wrench), expected, RTOL, ATOL, f"tau at q={q} f={wrench}")


def test_forward_dynamics_with_flange_wrench(case):
    for q, qd, _, tau, wrench in case.states():
        fext = pinocchio_model.flange_fext(case.pin_model, case.robot, wrench)
        expected = pin.aba(case.pin_model, case.data, q, qd, tau, fext)
        actual = forward_dynamics(case.robot, q, qd, tau, wrench)
        assert_close(actual, expected, RTOL, ATOL, f"qdd at q={q} f={wrench}")
