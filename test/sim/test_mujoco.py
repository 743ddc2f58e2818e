"""The core against MuJoCo, an independent engine, on the MJCF the simulator generates (the
IRB-140, random DH and URDF-form models, one with prismatic joints, the public UR5 and Panda URDFs):
inverse dynamics (mj_inverse), bias forces at rest (gravity), the mass matrix and forward
dynamics (mj_forward's qacc). Viscous friction (MuJoCo's damping) and armature are on;
Coulomb friction is off (MuJoCo's frictionloss is a dry-friction constraint, not our tanh),
and so are the joint limits (constraints)."""

import dataclasses

import mujoco
import numpy as np
import pytest

from irb140_dynamics.core import Friction, forward_dynamics, gravity, irb140, mass_matrix, rnea
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.sim.engine import SimulatedArm
from irb140_dynamics.sim.mjcf import MINIMAL_INERTIA, mjcf, mujoco_model

from ..support.common import OFFSET_PAYLOAD, assert_close, loaded_irb140, random_model, random_states, random_urdf_model
from ..support.urdf_support import ARMS, arm_text

STATES = 100
TORQUE_ATOL = 1e-8  # N m, the figure; the agreement is ~1e-11
RTOL = 1e-10


def viscous_only(model, rng):
    """The model with random viscous friction and no Coulomb friction."""
    joints = tuple(dataclasses.replace(j, friction=Friction(rng.uniform(0.0, 3.0), 0.0)) for j in model.joints)
    return dataclasses.replace(model, joints=joints)


def without_coulomb(model):
    joints = tuple(dataclasses.replace(j, friction=Friction(j.friction.viscous, 0.0)) for j in model.joints)
    return dataclasses.replace(model, joints=joints)


def sliding(model, joints):
    """The model with these joints prismatic (a MuJoCo slide joint)."""
    kinds = tuple(dataclasses.replace(j, kind="prismatic") if i in joints else j for i, j in enumerate(model.joints))
    return dataclasses.replace(model, joints=kinds)


def public_arm(name):
    """A public URDF's arm (its own damping; Coulomb friction off) with an offset payload at the tip."""
    loaded = load_urdf(arm_text(name), tip_link=ARMS[name][1])
    return without_coulomb(loaded.model).with_payload(OFFSET_PAYLOAD)


MODELS = {
    "irb140": irb140,
    "irb140_offset_payload": loaded_irb140,
    "irb140_payload_viscous": lambda: viscous_only(loaded_irb140(), np.random.default_rng(1)),
    **{f"dh_n{n}": (lambda n=n: random_model(np.random.default_rng(300 + n), n)) for n in (1, 4, 7)},
    **{
        f"urdf_form_n{n}_viscous": (
            lambda n=n: viscous_only(random_urdf_model(np.random.default_rng(400 + n), n), np.random.default_rng(n))
        )
        for n in (1, 3, 6, 7)
    },
    "urdf_form_n5_prismatic_1_3": lambda: sliding(
        viscous_only(random_urdf_model(np.random.default_rng(405), 5), np.random.default_rng(5)), (1, 3)
    ),
    "ur5": lambda: public_arm("ur5"),
    "panda": lambda: public_arm("panda"),
}


class Case:
    def __init__(self, robot, seed=11):
        self.robot = robot
        self.mj_model = mujoco_model(robot, friction=True, limits=False)
        self.data = mujoco.MjData(self.mj_model)
        rng = np.random.default_rng(seed)
        self.Q, self.QD, self.QDD = random_states(rng, robot.n, STATES)
        self.TAU = rng.uniform(-100.0, 100.0, (STATES, robot.n))


@pytest.fixture(scope="module", params=list(MODELS), ids=list(MODELS))
def case(request):
    return Case(MODELS[request.param]())


def test_inverse_dynamics(case):
    d = case.data
    for q, qd, qdd in zip(case.Q, case.QD, case.QDD):
        d.qpos[:], d.qvel[:], d.qacc[:] = q, qd, qdd
        mujoco.mj_inverse(case.mj_model, d)
        assert_close(rnea(case.robot, q, qd, qdd), d.qfrc_inverse, RTOL, TORQUE_ATOL, f"tau at q={q}")


def test_bias_at_rest_is_gravity(case):
    d = case.data
    for q in case.Q:
        d.qpos[:], d.qvel[:] = q, 0.0
        mujoco.mj_forward(case.mj_model, d)
        assert_close(gravity(case.robot, q), d.qfrc_bias, RTOL, TORQUE_ATOL, f"g at q={q}")


def test_mass_matrix_with_armature(case):
    d = case.data
    M = np.zeros((case.robot.n, case.robot.n))
    for q in case.Q:
        d.qpos[:] = q
        mujoco.mj_forward(case.mj_model, d)
        mujoco.mj_fullM(case.mj_model, d, M)
        assert_close(mass_matrix(case.robot, q), M, RTOL, 1e-12, f"M at q={q}")


def test_forward_dynamics(case):
    d = case.data
    for q, qd, tau in zip(case.Q, case.QD, case.TAU):
        d.qpos[:], d.qvel[:], d.qfrc_applied[:] = q, qd, tau
        mujoco.mj_forward(case.mj_model, d)
        assert_close(forward_dynamics(case.robot, q, qd, tau), d.qacc, 1e-9, 1e-9, f"qdd at q={q}")


def test_the_engine_is_not_blind_to_a_wrong_payload():
    """The comparison can fail: MuJoCo's arm with another payload disagrees by far more."""
    light = Case(irb140())
    d, q = light.data, light.Q[0]
    d.qpos[:] = q
    mujoco.mj_forward(light.mj_model, d)
    assert np.abs(gravity(loaded_irb140(), q) - d.qfrc_bias).max() > 1.0


def test_massless_links_get_the_minimal_inertia_and_nothing_else_changes():
    robot = loaded_irb140()
    m = mujoco_model(robot)
    masses = [j.link.mass for j in robot.joints] + [robot.payload.mass]
    np.testing.assert_array_equal(m.body_mass[1:], [x if x > 0 else MINIMAL_INERTIA for x in masses])
    assert m.body_inertia[3].tolist() == [MINIMAL_INERTIA] * 3  # link 3: no mass, no inertia
    np.testing.assert_allclose(sorted(m.body_inertia[2]), sorted(robot.joints[1].link.inertia[:3]), rtol=1e-14)


def test_joint_extras_and_limits_are_carried_over():
    robot = viscous_only(random_urdf_model(np.random.default_rng(5), 4, friction=True), np.random.default_rng(2))
    joints = tuple(
        dataclasses.replace(j, friction=Friction(j.friction.viscous, 1.5 + i), position_limits=(-1.0 - i, 2.0))
        for i, j in enumerate(robot.joints)
    )
    robot = dataclasses.replace(robot, joints=joints)
    m = mujoco_model(robot, timestep=0.0005)
    np.testing.assert_array_equal(m.dof_armature, [j.armature for j in robot.joints])
    np.testing.assert_array_equal(m.dof_damping, [j.friction.viscous for j in robot.joints])
    np.testing.assert_array_equal(m.dof_frictionloss, [1.5, 2.5, 3.5, 4.5])
    np.testing.assert_array_equal(m.jnt_range, [j.position_limits for j in robot.joints])
    assert m.jnt_limited.all() and m.opt.timestep == 0.0005
    np.testing.assert_array_equal(m.opt.gravity, robot.gravity)
    bare = mujoco_model(robot, friction=False, limits=False)
    assert not bare.dof_damping.any() and not bare.dof_frictionloss.any() and not bare.jnt_limited.any()


def test_bad_options_are_refused():
    with pytest.raises(ValueError, match="integrator"):
        mjcf(irb140(), integrator="leapfrog")
    with pytest.raises(ValueError, match="timestep"):
        mjcf(irb140(), timestep=0.0)


def test_a_tree_nests_its_bodies_along_parent_and_mimic_joints_are_equalities():
    """Two arms on a torso (test_urdf_trees): MuJoCo's inverse dynamics, M and gravity are the
    core's; with its mimic joints (each a joint held by an equality, soft as MuJoCo's are), the
    accelerations of the independent joints from rest are the core's forward dynamics within
    1e-3 of their largest (the equality's regularisation), and a SimulatedArm held by the
    core's gravity torques stays put."""
    from ..core.test_urdf_trees import TWO_ARMS, _without_mimics

    model = load_urdf(_without_mimics(TWO_ARMS)).model
    assert not model.is_chain
    mm = mujoco_model(model, friction=False, limits=False)
    data = mujoco.MjData(mm)
    for q, qd, qdd in zip(*(np.random.default_rng(21).uniform(-1, 1, (5, model.n)) for _ in range(3))):
        data.qpos[:], data.qvel[:], data.qacc[:] = q, qd, qdd
        mujoco.mj_inverse(mm, data)
        assert_close(data.qfrc_inverse, rnea(model, q, qd, qdd) - model.friction.torques(qd), 1e-9, 1e-9)
        M = np.zeros((model.n, model.n))
        mujoco.mj_forward(mm, data)
        mujoco.mj_fullM(mm, data, M)
        assert_close(M, mass_matrix(model, q), 1e-9, 1e-9)
    model = load_urdf(TWO_ARMS).model
    mm = mujoco_model(model, friction=False, limits=False)
    assert (mm.nq, mm.neq) == (len(model.joints), 2)
    data = mujoco.MjData(mm)
    for q in np.random.default_rng(22).uniform(-0.8, 0.8, (3, model.n)):
        data.qpos[:], data.qvel[:] = model.all_positions(q), 0.0
        mujoco.mj_forward(mm, data)
        expected = forward_dynamics(model, q, np.zeros(model.n), np.zeros(model.n))
        assert np.abs(data.qacc[list(model.independent)] - expected).max() < 1e-3 * np.abs(expected).max()
    arm = SimulatedArm(model, 0.001)
    q = np.array([0.3, -0.4, 0.5, 0.2, 0.1])
    arm.reset(q)
    for _ in range(500):
        arm.step(gravity(model, q))
    assert np.abs(arm.q - q).max() < 1e-6 and arm.q.shape == (model.n,)
    assert np.abs(arm.data.qpos - model.all_positions(q)).max() < 1e-6  # each mimic joint where it follows
