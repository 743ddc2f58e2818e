"""The virtual force sensor's numbers: the flange Jacobian in both frames and the joint
origins against Pinocchio (its own URDF parser), the wrench recovered from J^T F, least
squares and minimum norm, damping only near a singularity; the display scales."""

import numpy as np
import pinocchio as pin
import pytest

from irb140_dynamics.core import RobotModel, irb140
from irb140_dynamics.core.io.urdf import export_urdf, load_urdf
from irb140_dynamics.core.kinematics import flange_pose, joint_origins, joint_origins_and_flange
from irb140_dynamics.core.monitoring import display
from irb140_dynamics.core.monitoring.wrench import (
    MAX_DAMPING,
    SINGULAR_THRESHOLD,
    flange_jacobian_in,
    flange_wrench,
    in_base_axes,
    wrench_of,
)

from ..support.urdf_support import ARMS, arm_text, pinocchio_of

IRB140_TEXT = export_urdf(irb140())
ARM_CASES = {"irb140": (IRB140_TEXT, "flange"), **{name: (arm_text(name), tip) for name, (_, tip) in ARMS.items()}}


@pytest.fixture(scope="module", params=list(ARM_CASES))
def arm(request):
    """(our model, Pinocchio's model and data, the tip frame's id) of one URDF arm."""
    text, tip = ARM_CASES[request.param]
    loaded = load_urdf(text, tip_link=tip)
    pm = pinocchio_of(text, loaded.held_joints)
    return loaded.model, pm, pm.createData(), pm.getFrameId(tip)


def regular_poses(model, count, seed=0):
    """Random poses away from singularities (J's smallest singular value over 2x the threshold)."""
    rng, poses = np.random.default_rng(seed), []
    for q in rng.uniform(-1.5, 1.5, (1000, model.n)):
        if flange_wrench(model, q, np.zeros(model.n)).smallest_singular_value > 2 * SINGULAR_THRESHOLD:
            poses.append(q)
            if len(poses) == count:
                return poses
    raise AssertionError("no regular pose found")


def test_jacobian_in_both_frames_is_pinocchios(arm):
    model, pm, data, frame = arm
    for q in np.random.default_rng(1).uniform(-2.0, 2.0, (5, model.n)):
        pin.computeJointJacobians(pm, data, q)
        pin.updateFramePlacements(pm, data)
        for ours, theirs in (("tip", pin.LOCAL), ("base", pin.LOCAL_WORLD_ALIGNED)):
            expected = pin.getFrameJacobian(pm, data, frame, theirs)
            np.testing.assert_allclose(flange_jacobian_in(model, q, ours), expected, atol=1e-10, err_msg=ours)


def test_joint_origins_are_pinocchios(arm):
    model, pm, data, _ = arm
    q = np.random.default_rng(2).uniform(-2.0, 2.0, model.n)
    pin.forwardKinematics(pm, data, q)
    expected = [data.oMi[pm.getJointId(name)].translation for name in model.joint_names]
    np.testing.assert_allclose(joint_origins(model, q), expected, atol=1e-10)


def test_one_pass_of_kinematics_gives_the_same_numbers(arm):
    # the markers' path: origins, pose, Jacobian and wrench from one pass, as the separate calls
    model, pm, data, frame = arm
    for q in np.random.default_rng(3).uniform(-2.0, 2.0, (3, model.n)):
        origins, pose, J = joint_origins_and_flange(model, q)
        np.testing.assert_array_equal(origins, joint_origins(model, q))
        np.testing.assert_array_equal(pose, flange_pose(model, q))
        np.testing.assert_array_equal(J, flange_jacobian_in(model, q, "base"))
        tau_ext = np.random.default_rng(4).uniform(-20.0, 20.0, model.n)
        for side in ("tip", "base"):
            np.testing.assert_array_equal(
                wrench_of(pose, J, tau_ext, side).vector, flange_wrench(model, q, tau_ext, side).vector
            )
    with pytest.raises(ValueError):
        wrench_of(pose, J, [np.nan] * model.n, "base")


@pytest.mark.parametrize("frame", ["tip", "base"])
def test_a_known_wrench_comes_back(arm, frame):
    """tau_ext = J^T F_true (J from Pinocchio) gives F_true back, plainly (no damping)."""
    model, pm, data, tip = arm
    rng = np.random.default_rng(3)
    reference = {"tip": pin.LOCAL, "base": pin.LOCAL_WORLD_ALIGNED}[frame]
    for q in regular_poses(model, 5):
        F_true = np.concatenate([rng.normal(0.0, 30.0, 3), rng.normal(0.0, 5.0, 3)])
        J = pin.computeFrameJacobian(pm, data, q, tip, reference)
        wrench = flange_wrench(model, q, J.T @ F_true, frame)
        assert wrench.damping == 0.0 and not wrench.near_singularity and wrench.frame == frame
        np.testing.assert_allclose(wrench.vector, F_true, atol=1e-8 * np.abs(F_true).max())


def test_the_frames_are_one_wrench_turned():
    model = irb140()
    q = regular_poses(model, 1, seed=4)[0]
    tau_ext = np.random.default_rng(5).normal(0.0, 20.0, 6)
    tip, base = flange_wrench(model, q, tau_ext, "tip"), flange_wrench(model, q, tau_ext, "base")
    np.testing.assert_allclose(in_base_axes(flange_pose(model, q), tip.vector), base.vector, atol=1e-9)


def test_seven_joints_least_squares_and_three_minimum_norm():
    """Panda: torques no wrench explains give the least-squares fit; a 3-joint arm: of the
    wrenches that explain the torques, the one of least norm (both the pseudo-inverse's)."""
    loaded = load_urdf(arm_text("panda"), tip_link=ARMS["panda"][1])
    small = RobotModel(irb140().joints[:3])  # the IRB-140's arm without its wrist
    for model in (loaded.model, small):
        q = regular_poses(model, 1, seed=7)[0]
        tau_ext = np.random.default_rng(8).normal(0.0, 10.0, model.n)
        J = flange_jacobian_in(model, q, "tip")
        wrench = flange_wrench(model, q, tau_ext, "tip")
        np.testing.assert_allclose(wrench.vector, np.linalg.pinv(J.T) @ tau_ext, atol=1e-9)
    # the minimum norm one explains the torques exactly
    np.testing.assert_allclose(J.T @ wrench.vector, tau_ext, atol=1e-9)


def test_singular_pose_is_finite_damped_and_flagged():
    model = irb140()
    q = np.zeros(6)  # wrist axes 4 and 6 aligned
    huge = flange_wrench(model, q, [0.0, 0.0, 0.0, 1.0, 0.0, 1e-3])
    assert huge.near_singularity and huge.smallest_singular_value < 1e-12
    assert huge.damping == pytest.approx(MAX_DAMPING)
    assert np.isfinite(huge.vector).all() and np.abs(huge.vector).max() < 1e3


def test_damping_starts_at_the_threshold_continuously():
    """Along a path into the wrist singularity (q5 -> 0) the damping is zero down to the
    threshold and grows from zero below it; the estimate has no jump there."""
    model = irb140()
    tau_ext = np.array([1.0, -2.0, 3.0, 0.5, 0.2, -0.3])
    q5s = np.linspace(0.4, 0.0, 801)
    wrenches = [flange_wrench(model, [0.2, -0.3, 0.4, 0.3, q5, 0.1], tau_ext) for q5 in q5s]
    sigmas = np.array([w.smallest_singular_value for w in wrenches])
    damping = np.array([w.damping for w in wrenches])
    assert sigmas[0] > SINGULAR_THRESHOLD > sigmas[-1]
    assert (damping[sigmas >= SINGULAR_THRESHOLD] == 0.0).all()
    assert (damping[sigmas < SINGULAR_THRESHOLD] > 0.0).all()
    crossing = np.flatnonzero(sigmas < SINGULAR_THRESHOLD)[0]
    assert damping[crossing] < 0.1 * MAX_DAMPING
    step = np.abs(wrenches[crossing].vector - wrenches[crossing - 1].vector).max()
    typical = np.abs(np.diff([w.vector for w in wrenches[crossing - 10 : crossing]], axis=0)).max()
    assert step < 3 * typical + 1e-9


def test_bad_input_is_refused():
    model = irb140()
    with pytest.raises(ValueError, match="tau_ext"):
        flange_wrench(model, np.zeros(6), [np.nan] * 6)
    with pytest.raises(ValueError, match="frame"):
        flange_wrench(model, np.zeros(6), np.zeros(6), "world")


def test_colour_scale():
    assert display.load_colour(0.0) == display.GREEN
    assert display.load_colour(display.YELLOW_AT) == display.YELLOW
    assert display.load_colour(1.0) == display.RED == display.load_colour(5.0)
    assert display.load_colour(None) == display.GREY
    assert display.load_colour(0.35) == pytest.approx((0.5, 1.0, 0.0))
    assert display.load_colour(0.85) == pytest.approx((1.0, 0.5, 0.0))
    assert display.joint_loads([10.0, -85.2, 3.0, 1.0], [20.0, 100.0, np.inf, 0.0]) == [0.5, 0.852, None, None]
    assert display.load_label("joint_3", -85.2, 0.81) == "joint_3 81 % (-85.2 N m)"
    assert display.load_label("joint_1", 85.2, None) == "joint_1 (85.2 N m, no limit)"


def test_payload_sphere_and_arrow_sizes():
    # a 6 kg aluminium ball: (4/3) pi r^3 2700 = 6
    assert display.payload_diameter(6.0) == pytest.approx(2 * (6.0 / (4 / 3 * np.pi * 2700)) ** (1 / 3))
    assert display.payload_diameter(6.0) == pytest.approx(0.1619, abs=1e-4)
    assert display.payload_diameter(0.0) == display.MIN_PAYLOAD_DIAMETER
    np.testing.assert_allclose(display.arrow_end([1.0, 0.0, 0.0], [0.0, 20.0, 0.0]), [1.0, 0.2, 0.0])
    long = display.arrow_end([0.0, 0.0, 0.0], [1e6, 0.0, 0.0])
    np.testing.assert_allclose(long, [display.MAX_ARROW, 0.0, 0.0])


def test_huge_forces_and_torques_are_labelled_with_finite_numbers():
    """Efforts near 1e300 give forces whose length overflows: the label stays a finite
    number (with an exponent, not 300 digits), the arrow its longest along the force."""
    huge = [1e300, -1e300, 5e299]
    assert display.force_label(huge) == "1.5e+300 N"
    assert display.force_label([1.5e308, 1.5e308, 1.5e308]) == f"{display.LARGEST:.3g} N"
    assert display.force_label([30.0, 40.0, 0.0]) == "50.0 N"
    end = display.arrow_end([1.0, 0.0, 0.0], huge)
    np.testing.assert_allclose(end, [1.0, 0.0, 0.0] + display.MAX_ARROW * np.array(huge) / 1.5e300)
    assert display.load_label("joint_2", 1e300, None) == "joint_2 (1e+300 N m, no limit)"
    assert display.load_label("joint_2", -2e300, 1e298) == "joint_2 1e+300 % (-2e+300 N m)"
