"""The regressor of arms with mimic joints: Y = G^T Y_all, so that Y pi is the core's rnea
(friction and armature included) and the base parameters follow.

On a chain whose mimic joints are a parallelogram's (one before the joint it follows in the
file, multiplier -0.6, offset 0.3), a gripper's finger (multiplier -1, offset 0.05, with
Coulomb friction) and a prismatic one (multiplier 0.5, offset 0.01), and on a two-arm tree
with mimic joints (test_urdf_trees' TWO_ARMS); viscous friction and armature on every
joint, Coulomb friction where the model takes it (a mimic joint's with multiplier +-1)."""

from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics.core import Friction, rnea, rnea_batch
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.regressor import inertial_parameters, parameter_count, regressor, regressor_batch
from irb140_dynamics.identification.base import find_base_parameters

from .test_urdf_trees import TWO_ARMS, _joint, _link

MIMIC_CHAIN = f"""<robot name="mimic_chain">
  <link name="base"/>
  {_joint("j1", "base", "l1", axis="0 0 1")}{_link("l1", 4.0)}
  {_joint("parallel", "l1", "l2", extra='<mimic joint="j3" multiplier="-0.6" offset="0.3"/>')}{_link("l2", 2.0)}
  {_joint("j2", "l2", "l3", axis="1 0 0")}{_link("l3", 1.5)}
  {_joint("j3", "l3", "l4")}{_link("l4", 1.0)}
  {_joint("finger", "l4", "l5", extra='<mimic joint="j3" multiplier="-1" offset="0.05"/>')}{_link("l5", 0.3)}
  {
    _joint(
        "slide", "l5", "l6", kind="prismatic", axis="0 0 1", extra='<mimic joint="j2" multiplier="0.5" offset="0.01"/>'
    )
}{_link("l6", 0.2)}
</robot>"""


def with_joint_terms(model):
    """The model with viscous friction and armature on every joint, Coulomb friction on every
    joint that takes it (not a mimic joint of multiplier other than +-1)."""
    mimics = model.mimics or (None,) * len(model.joints)
    joints = tuple(
        replace(
            joint,
            friction=Friction(0.1 + 0.05 * i, 0.3 if mimic is None or abs(mimic.multiplier) == 1.0 else 0.0),
            armature=0.01 * (i + 1),
        )
        for i, (joint, mimic) in enumerate(zip(model.joints, mimics))
    )
    return replace(model, joints=joints)


ARMS = {"chain with mimic joints": MIMIC_CHAIN, "tree with mimic joints": TWO_ARMS}


@pytest.fixture(scope="module", params=list(ARMS))
def arm(request):
    return with_joint_terms(load_urdf(ARMS[request.param]).model)


def test_the_chain_is_one_with_its_mimic_joints_as_written():
    model = load_urdf(MIMIC_CHAIN).model
    assert model.parent == (-1, 0, 1, 2, 3, 4) and model.joint_names == ("j1", "j2", "j3")
    assert [(m.joint, m.multiplier, m.offset) if m else None for m in model.mimics] == [
        None,
        ("j3", -0.6, 0.3),
        None,
        None,
        ("j3", -1.0, 0.05),
        ("j2", 0.5, 0.01),
    ]


def test_regressor_times_parameters_is_rnea(arm):
    assert arm.mimics is not None and len(arm.joints) > arm.n
    rng = np.random.default_rng(4)
    Q, QD, QDD = (rng.uniform(-1.5, 1.5, (20, arm.n)) for _ in range(3))
    pi = inertial_parameters(arm)
    Y = regressor_batch(arm, Q, QD, QDD)
    assert Y.shape == (20, arm.n, parameter_count(arm)) and pi.shape == (parameter_count(arm),)
    tau = rnea_batch(arm, Q, QD, QDD)
    assert np.abs(tau).max() > 1.0
    np.testing.assert_allclose(Y @ pi, tau, rtol=1e-9, atol=1e-9)
    for k in (0, 7):
        single = regressor(arm, Q[k], QD[k], QDD[k])
        np.testing.assert_allclose(single, Y[k], rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(single @ pi, rnea(arm, Q[k], QD[k], QDD[k]), rtol=1e-9, atol=1e-9)
    base = find_base_parameters(arm)  # the base parameters: Y_b beta == Y pi
    assert 0 < base.count < len(pi)
    np.testing.assert_allclose(base.columns(Y) @ base.of(pi), tau, rtol=1e-9, atol=1e-9)


def test_a_mimic_joints_friction_and_armature_columns_are_carried_by_its_joint():
    """Row k of joint i's terms (i following q_k with multiplier m): m^2 qd_k, tanh(qd_k /
    v_s) (0 unless |m| = 1) and m^2 qdd_k; no other row holds them."""
    model = load_urdf(MIMIC_CHAIN).model
    names = [j.name for j in model.joints]
    q, qd, qdd = np.zeros(model.n), np.array([0.2, -0.7, 0.004]), np.array([1.0, 2.0, 3.0])
    Y = regressor(model, q, qd, qdd)
    terms = Y[:, 10 * len(names) :].reshape(model.n, len(names), 3)
    v_s = model.smoothing_velocity
    for joint, k, m in (("parallel", 2, -0.6), ("finger", 2, -1.0), ("slide", 1, 0.5), ("j3", 2, 1.0)):
        i = names.index(joint)
        expected = np.zeros((model.n, 3))
        expected[k] = m * m * qd[k], np.tanh(qd[k] / v_s) if abs(m) == 1.0 else 0.0, m * m * qdd[k]
        np.testing.assert_allclose(terms[:, i], expected, rtol=1e-15, atol=0.0)
