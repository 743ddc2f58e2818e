"""URDF -> RobotModel against Pinocchio's URDF parser on the same text: the UR5 and the Panda
(fingers held at zero), and random URDFs with fixed joints, side branches, continuous
joints and turned inertials; what the loader reads and reports."""

import math

import numpy as np
import pinocchio as pin
import pytest

from irb140_dynamics.core import flange_pose, gravity, mass_matrix, rnea
from irb140_dynamics.core.io.urdf import CONTINUOUS_LIMITS, load_urdf

from ..support.common import OFFSET_PAYLOAD, assert_close, random_states
from ..support.urdf_support import ARMS, arm_text, full_mass_matrix, pinocchio_of, pinocchio_rnea, random_urdf

STATES = 200
RTOL, ATOL = 1e-9, 1e-12


def pin_configuration(model: pin.Model, q) -> np.ndarray:
    """Pinocchio's q for joint angles q: (cos, sin) for its unbounded (continuous) joints."""
    parts = []
    for joint, angle in zip(list(model.joints)[1:], q):
        parts += [math.cos(angle), math.sin(angle)] if joint.nq == 2 else [angle]
    return np.array(parts)


class Case:
    def __init__(self, text, tip, held=None, payload=None, seed=11):
        self.loaded = load_urdf(text, tip_link=tip)
        self.robot = self.loaded.model if payload is None else self.loaded.model.with_payload(payload)
        self.pin_model = pinocchio_of(text, held if held is not None else self.loaded.held_joints, tip, payload)
        self.data = self.pin_model.createData()
        self.tip = tip
        self.Q, self.QD, self.QDD = random_states(np.random.default_rng(seed), self.robot.n, STATES)


def arm_case(name, payload=None):
    file, tip = ARMS[name]
    return Case(arm_text(name), tip, payload=payload)


def random_case(n, seed):
    text, held = random_urdf(np.random.default_rng(seed), n)
    return Case(text, "tip", held, payload=OFFSET_PAYLOAD, seed=seed)


CASES = {
    "ur5": lambda: arm_case("ur5"),
    "panda": lambda: arm_case("panda"),
    "ur5_payload": lambda: arm_case("ur5", OFFSET_PAYLOAD),
    "panda_payload": lambda: arm_case("panda", OFFSET_PAYLOAD),
    **{f"random_n{n}": (lambda n=n: random_case(n, 30 + n)) for n in (1, 4, 7)},
}


@pytest.fixture(scope="module", params=list(CASES), ids=list(CASES))
def case(request):
    return CASES[request.param]()


def test_same_joints_and_mass_as_pinocchio(case):
    assert case.pin_model.nv == case.robot.n
    assert list(case.pin_model.names)[1:] == list(case.robot.joint_names)
    moving_mass = sum(inertia.mass for inertia in list(case.pin_model.inertias)[1:])
    assert sum(body.mass for body in case.robot.bodies) == pytest.approx(moving_mass, rel=1e-14)


def test_rnea(case):
    for q, qd, qdd in zip(case.Q, case.QD, case.QDD):
        expected = pinocchio_rnea(
            case.pin_model, case.data, pin_configuration(case.pin_model, q), qd, qdd, case.robot.smoothing_velocity
        )
        assert_close(rnea(case.robot, q, qd, qdd), expected, RTOL, ATOL, f"tau at q={q}")


def test_gravity(case):
    for q in case.Q:
        expected = pin.computeGeneralizedGravity(case.pin_model, case.data, pin_configuration(case.pin_model, q))
        assert_close(gravity(case.robot, q), expected, RTOL, ATOL, f"g at q={q}")


def test_mass_matrix(case):
    for q in case.Q:
        expected = full_mass_matrix(case.pin_model, case.data, pin_configuration(case.pin_model, q))
        assert_close(mass_matrix(case.robot, q), expected, RTOL, ATOL, f"M at q={q}")


def test_flange_is_the_tip_link_frame(case):
    frame = case.pin_model.getFrameId(case.tip)
    for q in case.Q[:20]:
        pin.framesForwardKinematics(case.pin_model, case.data, pin_configuration(case.pin_model, q))
        assert_close(flange_pose(case.robot, q), case.data.oMf[frame].homogeneous, RTOL, ATOL, f"q={q}")


def test_panda_limits_friction_and_held_fingers():
    loaded = load_urdf(arm_text("panda"), tip_link="panda_hand_tcp")
    assert (loaded.base_link, loaded.tip_link) == ("panda_link0", "panda_hand_tcp")
    assert sorted(loaded.held_joints) == ["panda_finger_joint1", "panda_finger_joint2"]
    joint4 = loaded.model.joints[3]
    assert joint4.position_limits == (-3.0718, -0.0698)
    assert (joint4.torque_limit, joint4.velocity_limit) == (87.0, 2.175)
    assert (joint4.friction.viscous, joint4.friction.coulomb) == (0.003, 0.0)
    assert loaded.model.flange.xyz == pytest.approx((0.0, 0.0, 0.2104), abs=1e-15)


def test_ur5_transmission_joints_are_not_joints_and_base_link_may_be_below_the_root():
    text = arm_text("ur5")
    from_root = load_urdf(text, tip_link="tool0")
    from_base = load_urdf(text, base_link="base_link", tip_link="tool0")
    assert from_root.base_link == "world" and from_root.held_joints == ()
    assert from_root.model.joint_names == from_base.model.joint_names
    assert from_root.model.joints[0].torque_limit == 150.0
    q = np.random.default_rng(5).uniform(-3, 3, 6)
    assert_close(gravity(from_base.model, q), gravity(from_root.model, q), 1e-15, 1e-15)


def test_several_leaves_and_no_tip_link_give_every_moving_joint():
    """The UR5's leaves hang from fixed joints: its tree is its chain, to the last moving
    link; the Panda's fingers make a tree, the second finger a mimic joint of the first."""
    ur5 = load_urdf(arm_text("ur5")).model
    assert ur5.joint_names == load_urdf(arm_text("ur5"), tip_link="tool0").model.joint_names
    assert ur5.parent == (-1, 0, 1, 2, 3, 4)
    panda = load_urdf(arm_text("panda"))
    assert panda.model.joint_names == tuple(f"panda_joint{i}" for i in range(1, 8)) + ("panda_finger_joint1",)
    assert panda.model.parent == (-1, 0, 1, 2, 3, 4, 5, 6, 6)
    assert panda.model.mimics[-1].joint == "panda_finger_joint1" and panda.tip_link == "panda_rightfinger"


def test_continuous_joint_gets_the_wide_default_range():
    text, _ = random_urdf(np.random.default_rng(3), 3)
    model = load_urdf(text, tip_link="tip").model
    assert model.joints[2].position_limits == CONTINUOUS_LIMITS
    assert model.joints[0].position_limits == (-2.5, 2.5)


def test_angles_written_to_eleven_digits_are_right_angles():
    """The UR5 writes pi/2 as 1.57079632679: the origin is exactly a quarter turn."""
    shoulder_lift = load_urdf(arm_text("ur5"), tip_link="tool0").model.joints[1]
    assert shoulder_lift.origin.rpy == (0.0, math.pi / 2, 0.0)
    assert (
        load_urdf(arm_text("ur5").replace("1.57079632679", "1.5708"), tip_link="tool0").model.joints[1].origin.rpy[1]
        == 1.5708
    )
