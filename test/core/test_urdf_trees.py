"""Whole kinematic trees and mimic joints against Pinocchio, and the tree's identities.

Every URDF of example-robot-data is read as one fixed-base tree (``load_urdf`` with no
tip_link: every moving joint below the root) and compared with Pinocchio on rnea, gravity
and M at random states: 1e-9 relative (see support.pinocchio_trees; mimic joints as
Pinocchio's ``mimic=True`` follows them, or by virtual work where it refuses them). In the
suite a seeded few files and the Panda (a tree with a mimic joint), every file with
IRB140_SWEEP=full; the mimic chains of Romeo's and TALOS' hands are in the corpus test. Small handmade trees check
what Pinocchio cannot refuse to check: a mimic joint before its joint in the file, with a
multiplier and an offset; and the other algorithms on a tree by their identities.
"""

from pathlib import Path

import numpy as np
import pytest

from irb140_dynamics.core import (
    ModelError,
    RobotModel,
    coriolis,
    coriolis_matrix,
    forward_dynamics,
    gravity,
    mass_matrix,
    rnea,
)
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.core.derivatives import forward_dynamics_derivatives, rnea_derivatives
from irb140_dynamics.core.kinematics import flange_jacobian, flange_pose, link_jacobian, link_pose
from irb140_dynamics.core.regressor import regressor
from irb140_dynamics.core.urdf import load_urdf
from irb140_dynamics.identification.base import find_base_parameters

from ..support.common import full_sweep
from ..support.pinocchio_trees import corpus_files, pinocchio_of, reference, worst_error
from ..support.two_arms import TWO_ARMS, _joint, _link  # noqa: F401 (the trees' tests import them from here)

RTOL = 1e-9
QUICK_FILES = 6  # compared in the suite (seeded), besides the mimic ones
# refusals a whole file may get, each one line: no moving joint at all, a mimic joint of a
# joint the file does not have (alex_psyonic_hands), not a URDF (ur3.urdf is a xacro stub)
REFUSALS = ("no revolute, continuous or prismatic joint", "which is not a moving joint of the model", "no <link>")


FILES = corpus_files()


@pytest.mark.skipif(not FILES, reason="example-robot-data is not installed")
def test_every_tree_of_example_robot_data_agrees_with_pinocchio():
    rng = np.random.default_rng(40)
    loaded, refused = [], []
    for path in FILES:
        text = Path(path).read_text()
        try:
            loaded.append((path, text, load_urdf(text).model))
        except ModelError as refusal:
            assert "\n" not in str(refusal) and any(reason in str(refusal) for reason in REFUSALS), (path, refusal)
            refused.append(path)
    assert len(loaded) >= 65 and len(refused) <= 4
    with_mimics = [entry for entry in loaded if entry[2].mimics is not None]
    assert len(with_mimics) >= 6  # Baxter's, the Panda's, the PR2's grippers, Romeo's, TALOS', TIAGo's hands
    chosen = loaded
    if not full_sweep():
        others = [entry for entry in loaded if entry[2].mimics is None and len(entry[2].joints) <= 20]
        chosen = [others[k] for k in sorted(rng.choice(len(others), QUICK_FILES, replace=False))]
        chosen += [min(with_mimics, key=lambda entry: len(entry[2].joints))]  # the Panda: a tree with a mimic
    errors = {path.split("/robots/")[-1]: worst_error(text, model, rng, states=1) for path, text, model in chosen}
    assert all(error <= RTOL for error in errors.values()), errors


TIAGO_DUAL = [path for path in FILES if path.endswith("/tiago_dual.urdf")]


@pytest.mark.skipif(not TIAGO_DUAL, reason="example-robot-data is not installed")
def test_tiago_dual_loads_whole_with_its_101_joints_and_its_gravity_is_pinocchios():
    text = Path(TIAGO_DUAL[0]).read_text()
    loaded = load_urdf(text)  # the whole robot: base, torso, two arms, two hands, head
    model = loaded.model
    assert model.n == 101 and loaded.held_joints == ()
    q = np.random.default_rng(101).uniform(-1.5, 1.5, model.n)
    full, follows = pinocchio_of(text, model.mimics is not None)
    zero = np.zeros(model.n)
    _, g, _ = reference(full, follows, model, q, zero, zero, loaded.held_positions)
    assert np.max(np.abs(gravity(model, q) - g)) <= RTOL * np.max(np.abs(g))


def test_a_handmade_tree_with_mimic_joints_agrees_with_pinocchio():
    loaded = load_urdf(TWO_ARMS)
    model = loaded.model
    assert [j.name for j in model.joints] == ["torso", "l1", "l2", "r1", "finger_b", "r2", "finger_a"]
    assert model.parent == (-1, 0, 1, 0, 3, 3, 5)
    assert model.joint_names == ("torso", "l1", "l2", "r1", "r2")
    assert worst_error(TWO_ARMS, model, np.random.default_rng(3), states=3) <= RTOL
    # finger_b's damping is carried by r2: m^2 v
    assert model.friction.viscous.tolist() == [0.0, 0.0, 0.0, 0.0, 0.25 * 0.3]
    assert RobotModel.from_params(model.to_params()) == model  # the nodes' path: the parameter form


def test_the_tree_identities_hold():
    """Forward dynamics inverts rnea; the regressor's Y pi is rnea's torque; C qd is rnea at
    qdd = 0 without gravity; M is zero between the two arms; the Jacobian's columns are
    those of the joints a link hangs from, and move the link as a finite difference."""
    model = load_urdf(TWO_ARMS.replace('<mimic joint="r2" multiplier="-0.5" offset="0.01"/>', "")).model
    tree = load_urdf(_without_mimics(TWO_ARMS)).model
    rng = np.random.default_rng(7)
    for m in (model, tree):
        q, qd, qdd = rng.uniform(-1, 1, m.n), rng.uniform(-1, 1, m.n), rng.uniform(-1, 1, m.n)
        tau = rnea(m, q, qd, qdd)
        np.testing.assert_allclose(forward_dynamics(m, q, qd, tau), qdd, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(
            coriolis(m, q, qd), rnea(m, q, qd, 0 * qd) - gravity(m, q) - _friction(m, qd), atol=1e-12
        )
        M = mass_matrix(m, q)
        left, right = m.joint_names.index("l2"), m.joint_names.index("r1")
        assert M[left, right] == 0.0 and M[right, left] == 0.0
        assert np.all(np.linalg.eigvalsh(M) > 0)
    q, qd, qdd = rng.uniform(-1, 1, tree.n), rng.uniform(-1, 1, tree.n), rng.uniform(-1, 1, tree.n)
    Y = regressor(tree, q, qd, qdd)
    pi = _parameters(tree)
    np.testing.assert_allclose(Y @ pi, rnea(tree, q, qd, qdd), rtol=1e-12, atol=1e-12)
    base = find_base_parameters(tree)  # the tree's base parameters: Y_b beta = Y pi
    assert 0 < base.count < len(pi)
    np.testing.assert_allclose(base.columns(Y) @ base.of(pi), Y @ pi, rtol=1e-9, atol=1e-9)
    J = link_jacobian(model, q[: model.n], "l2")
    assert not J[:, model.joint_names.index("r1")].any()
    step = 1e-6
    for k in range(model.n):
        dq = np.zeros(model.n)
        dq[k] = step
        moved = (
            link_pose(model, q[: model.n] + dq, "l2")[:3, 3] - link_pose(model, q[: model.n] - dq, "l2")[:3, 3]
        ) / (2 * step)
        np.testing.assert_allclose(J[:3, k], moved, atol=1e-8)
    np.testing.assert_allclose(
        flange_jacobian(model, q[: model.n]), link_jacobian(model, q[: model.n], "finger_a"), atol=1e-15
    )


def _without_mimics(text: str) -> str:
    for mimic in (
        '<mimic joint="r2" multiplier="-0.5" offset="0.01"/>',
        '<mimic joint="r2" multiplier="2.0" offset="0.2"/>',
    ):
        text = text.replace(mimic, "")
    return text


def _friction(model, qd):
    return 0.0 if model.friction is None else model.friction.torques(qd)


def _parameters(model) -> np.ndarray:
    """pi of the regressor (see core.regressor): per link m, m c, the inertia about its origin
    in Pinocchio's order; then per joint viscous, Coulomb friction and armature."""
    from irb140_dynamics.core.regressor import inertial_parameters

    return inertial_parameters(model)


@pytest.mark.parametrize("mimics", [False, True], ids=["tree", "tree with mimic joints"])
def test_derivatives_and_the_coriolis_matrix_on_a_tree_are_the_finite_differences(mimics):
    model = load_urdf(TWO_ARMS if mimics else _without_mimics(TWO_ARMS)).model
    rng = np.random.default_rng(11)
    q, qd, qdd = rng.uniform(-1, 1, model.n), rng.uniform(-1, 1, model.n), rng.uniform(-1, 1, model.n)
    dq, dqd, M = rnea_derivatives(model, q, qd, qdd)
    tau = rnea(model, q, qd, qdd)
    dqdd_dq, dqdd_dqd, Minv = forward_dynamics_derivatives(model, q, qd, tau)
    step, unit = 1e-6, np.eye(model.n)
    for k in range(model.n):
        up, down = q + step * unit[k], q - step * unit[k]
        np.testing.assert_allclose(
            dq[:, k], (rnea(model, up, qd, qdd) - rnea(model, down, qd, qdd)) / (2 * step), atol=1e-7
        )
        moved = (forward_dynamics(model, up, qd, tau) - forward_dynamics(model, down, qd, tau)) / (2 * step)
        np.testing.assert_allclose(dqdd_dq[:, k], moved, atol=1e-6)
        fast, slow = qd + step * unit[k], qd - step * unit[k]
        np.testing.assert_allclose(
            dqd[:, k], (rnea(model, q, fast, qdd) - rnea(model, q, slow, qdd)) / (2 * step), atol=1e-7
        )
        moved = (forward_dynamics(model, q, fast, tau) - forward_dynamics(model, q, slow, tau)) / (2 * step)
        np.testing.assert_allclose(dqdd_dqd[:, k], moved, atol=1e-6)
    np.testing.assert_allclose(M, mass_matrix(model, q), rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(Minv @ M, np.eye(model.n), atol=1e-9)
    np.testing.assert_allclose(forward_dynamics(model, q, qd, tau), qdd, atol=1e-9)
    C = coriolis_matrix(model, q, qd)  # C qd is the Coriolis torque, Mdot - 2C is skew-symmetric
    np.testing.assert_allclose(C @ qd, coriolis(model, q, qd), atol=1e-12)
    Mdot = (mass_matrix(model, q + step * qd) - mass_matrix(model, q - step * qd)) / (2 * step)
    np.testing.assert_allclose(Mdot - 2 * C, -(Mdot - 2 * C).T, atol=1e-8)


def test_the_momentum_terms_on_a_tree_with_mimic_joints():
    """The observer's [p, dT/dq] (see algorithms.momentum): p = M qd, and dT/dq the slope of
    T = qd^T M(q) qd / 2 (central differences)."""
    model = load_urdf(TWO_ARMS).model
    rng = np.random.default_rng(12)
    q, qd = rng.uniform(-1, 1, model.n), rng.uniform(-1, 1, model.n)
    terms = np.array(kernels_of(model).momentum.scalar(q.tolist(), qd.tolist()))
    np.testing.assert_allclose(terms[: model.n], mass_matrix(model, q) @ qd, rtol=1e-12, atol=1e-14)
    step, unit = 1e-6, np.eye(model.n)

    def energy(x):
        return 0.5 * qd @ mass_matrix(model, x) @ qd

    slope = [(energy(q + step * unit[k]) - energy(q - step * unit[k])) / (2 * step) for k in range(model.n)]
    np.testing.assert_allclose(terms[model.n :], slope, atol=1e-8)


def test_the_payload_analysis_refuses_a_tree_in_one_line():
    """Its proofs slice a chain: a tree's payload is the nodes' (payload.link)."""
    from irb140_dynamics.core import RigidBody
    from irb140_dynamics.core.payload.family import payload_family

    with pytest.raises(ValueError, match="takes a serial chain without mimic joints: load the URDF with its tip_link"):
        payload_family(load_urdf(TWO_ARMS).model, RigidBody(1.0))


def test_a_payload_and_a_flange_wrench_on_another_link_than_the_last():
    """flange_joint: the payload on the left arm's link (the flange placed there), against
    Pinocchio with the payload as a body on that joint; the flange wrench there is -J^T f."""
    from dataclasses import replace

    from irb140_dynamics.core import RigidBody
    from irb140_dynamics.core.model.joints import Placement

    from ..support.pinocchio_model import build

    tree = load_urdf(_without_mimics(TWO_ARMS).replace('type="prismatic"', 'type="revolute"')).model  # build's joints
    payload = RigidBody(2.5, (0.01, 0.02, 0.05), (0.01, 0.02, 0.015, 0.001, 0.0, 0.0))
    model = replace(tree, payload=payload, flange=Placement((0.0, 0.0, 0.1), (0.3, 0.0, 0.0)), flange_joint="l2")
    assert model.carrier == 2 and not model.is_chain
    assert RobotModel.from_params(model.to_params()) == model
    pm = build(model)  # the payload appended to the flange's joint
    rng = np.random.default_rng(8)
    for q, qd, qdd in zip(*(rng.uniform(-1, 1, (3, model.n)) for _ in range(3))):
        import pinocchio as pin

        tau = pin.rnea(pm, pm.createData(), q, qd, qdd)
        np.testing.assert_allclose(rnea(model, q, qd, qdd) - model.friction.torques(qd), tau, rtol=1e-10, atol=1e-10)
        M = pin.crba(pm, pm.createData(), q)
        np.testing.assert_allclose(mass_matrix(model, q), np.triu(M) + np.triu(M, 1).T, rtol=1e-10, atol=1e-10)
        pose = link_pose(model, q, "l2") @ model.flange.matrix()
        np.testing.assert_allclose(flange_pose(model, q), pose, atol=1e-15)
        wrench = rng.uniform(-5, 5, 6)  # on the flange, in the flange frame
        J = flange_jacobian(model, q)
        R = pose[:3, :3]
        expected = rnea(model, q, qd, qdd) - J.T @ np.concatenate([R @ wrench[:3], R @ wrench[3:]])
        np.testing.assert_allclose(rnea(model, q, qd, qdd, f_ext=wrench), expected, rtol=1e-10, atol=1e-10)


def test_the_flange_at_a_urdf_link_is_where_that_link_is():
    """with_flange_at: the payload's link named as in the URDF (a fixed bracket, a moving
    link), its pose that of the link in Pinocchio's model of the file."""
    import pinocchio as pin

    loaded = load_urdf(TWO_ARMS)
    full = pin.buildModelFromXML(TWO_ARMS)
    rng = np.random.default_rng(9)
    q = rng.uniform(-1, 1, loaded.model.n)
    pq = np.zeros(full.nq)
    for name, x in zip([j.name for j in loaded.model.joints], loaded.model.all_positions(q)):
        pq[full.joints[full.getJointId(name)].idx_q] = x
    data = full.createData()
    pin.framesForwardKinematics(full, data, pq)
    for link, joint in (("bracket", "torso"), ("la2", "l2"), ("fb", "finger_b")):
        model = loaded.with_flange_at(link)
        assert model.flange_joint in (joint, None) and model.carrier == [j.name for j in model.joints].index(joint)
        expected = data.oMf[full.getFrameId(link, pin.FrameType.BODY)].homogeneous
        np.testing.assert_allclose(flange_pose(model, q), expected, atol=1e-12)
    with pytest.raises(ValueError, match="'base' is not moved by the model's joints"):
        loaded.with_flange_at("base")


def test_a_floating_base_is_refused_naming_it_and_the_tree_below_it_is_read():
    """A humanoid written with its free-flyer joint: refused from the root, in one line
    naming the joint; from the link under it, the tree below, fixed there."""
    floating = TWO_ARMS.replace(
        '<link name="base"/>',
        '<link name="world"/><joint name="free" type="floating"><parent link="world"/><child link="base"/>'
        '<origin xyz="0 0 1" rpy="0 0 0"/></joint><link name="base"/>',
    )
    with pytest.raises(ModelError) as refusal:
        load_urdf(floating)
    assert str(refusal.value).startswith("URDF joint \"free\": a floating joint below 'world'")
    assert "name the link under it as base_link" in str(refusal.value) and "\n" not in str(refusal.value)
    below = load_urdf(floating, base_link="base").model
    assert below == load_urdf(TWO_ARMS).model
