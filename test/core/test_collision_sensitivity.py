"""Collision sensitivity from data (core.monitoring.sensitivity): the observer's peaks over a
recording, the thresholds from them, and the force at the flange they detect.

The detectable force is checked against torques made another way: RNEA with the force as
an external wrench on the flange (``rnea(..., f_ext)``, the flange's axes), on the IRB-140,
the UR5 from its URDF and an arm with a sliding joint; the peaks against a constant external torque the observer must
settle on (dr/dt = K (tau_ext - r)). That the settings are id_node's:
test/tools/test_calibrate_collision_tool.py.
"""

import math

import numpy as np
import pytest

from irb140_dynamics.core import flange_pose, irb140, rnea, rnea_batch
from irb140_dynamics.core.kinematics import flange_jacobian, flange_jacobians
from irb140_dynamics.core.monitoring.sensitivity import (
    AXES,
    CalibrationError,
    DetectableForces,
    ResidualPeaks,
    collision_thresholds,
    detectable_force_at,
)
from irb140_dynamics.core.urdf import load_urdf

from ..support.paths import URDF_DATA
from ..support.simulated_pushes import normal_motion


def ur5():
    return load_urdf((URDF_DATA / "ur5.urdf").read_text(), "base_link", "tool0").model


def prismatic_arm():
    """Turn, reach (a sliding joint: its threshold and load in N), wrist."""
    return load_urdf((URDF_DATA / "prismatic_arm.urdf").read_text()).model


ARMS = {"irb140": irb140, "ur5": ur5, "prismatic": prismatic_arm}


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_poses_jacobians_at_once_are_each_pose_s_bit_for_bit(name):
    """``flange_jacobians`` (what DetectableForces.add uses) is ``flange_jacobian`` at each pose,
    the same numbers; a shape that is not (N, n) poses is refused."""
    model = ARMS[name]()
    lower, upper = np.array([j.position_limits for j in model.joints]).T
    Q = lower + np.random.default_rng(3).random((40, model.n)) * (upper - lower)
    assert np.array_equal(flange_jacobians(model, Q), np.array([flange_jacobian(model, q) for q in Q]))
    assert flange_jacobians(model, Q[:0]).shape == (0, 6, model.n)
    with pytest.raises(ValueError, match="poses shaped"):
        flange_jacobians(model, Q[:, :-1])


def external_torques(model, q, force):
    """tau_ext [N m] of ``force`` [N, base axes] on the flange origin, by RNEA: the torque
    the joints no longer have to make (rnea balances the environment's wrench)."""
    R = flange_pose(model, q)[:3, :3]
    zero = np.zeros(model.n)
    return rnea(model, q, zero, zero) - rnea(model, q, zero, zero, f_ext=np.concatenate([R.T @ force, np.zeros(3)]))


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_detectable_force_is_where_rnea_torques_first_reach_a_threshold(name):
    model = ARMS[name]()
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = rng.uniform(-2.0, 2.0, model.n)
        thresholds = rng.uniform(0.5, 20.0, model.n)
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        f = detectable_force_at(model, q, thresholds, d)
        at = np.abs(external_torques(model, q, f * d)) / thresholds
        assert at.max() == pytest.approx(1.0, rel=1e-9)  # one joint exactly at its threshold
        assert (np.abs(external_torques(model, q, 0.999 * f * d)) < thresholds).all()  # none below it
        assert detectable_force_at(model, q, thresholds, -d) == pytest.approx(f, rel=1e-12)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_the_figure_of_each_direction_is_the_worst_pose_s(name):
    model = ARMS[name]()
    Q = normal_motion(model, 4).evaluate(np.linspace(0.0, 10.0, 200))[0]
    thresholds = np.linspace(2.0, 12.0, model.n)
    forces = DetectableForces(model, thresholds)
    t = np.arange(len(Q)) * 0.05
    forces.add(t[:120], Q[:120])  # in two parts, as chunks come
    forces.add(t[120:], Q[120:])
    found = forces.result()
    assert [f.direction for f in found] == list(AXES)
    for f in found:
        unit = np.zeros(3)
        unit["xyz".index(f.direction[1])] = 1.0 if f.direction[0] == "+" else -1.0
        each = np.array([detectable_force_at(model, q, thresholds, unit) for q in Q])
        if np.isinf(each).any():  # the sliding arm's z: no joint feels it
            unfelt = np.flatnonzero(np.isinf(each))
            assert f.force is None and f.undetected == len(unfelt) and f.time == t[unfelt[0]]
            continue
        worst = int(np.argmax(each))
        assert f.force == pytest.approx(each[worst], rel=1e-12) and f.time == t[worst] and f.undetected == 0
        torques = np.abs(external_torques(model, Q[worst], f.force * unit)) / thresholds
        assert int(np.argmax(torques)) == f.joint
    assert name != "prismatic" or [f.direction for f in found if f.force is None] == ["+z", "-z"]


def test_a_pose_where_no_joint_feels_the_force_has_no_figure():
    """A planar arm of turning joints (every axis along z) feels no force along z in any
    pose: those poses are counted, and the direction has no figure (never an infinite one)."""
    from irb140_dynamics.core import DH, Joint, RigidBody, RobotModel

    link = RigidBody(1.0, (0.1, 0.0, 0.0), (0.01, 0.01, 0.01, 0.0, 0.0, 0.0))
    planar = RobotModel(tuple(Joint(f"j{i}", DH(0.3, 0.0, 0.0, 0.0), link, (-3.0, 3.0)) for i in range(3)))
    forces = DetectableForces(planar, [1.0, 1.0, 1.0])
    forces.add([0.0, 0.1, 0.2], [[0.1, 0.2, 0.3], [0.5, -0.4, 1.0], [1.0, 1.0, 1.0]])
    by = {f.direction: f for f in forces.result()}
    assert by["+z"].force is None and by["+z"].undetected == 3 and by["-z"].time == 0.0
    assert by["+x"].force is not None and math.isfinite(by["+x"].force) and by["+x"].undetected == 0
    assert math.isinf(detectable_force_at(planar, [0.1, 0.2, 0.3], [1.0, 1.0, 1.0], [0.0, 0.0, 1.0]))


def recorded(model, tau_ext, seconds=3.0, rate=500.0):
    """(t, Q, QD, efforts) of the model along a normal motion, the efforts exact less a
    constant external torque ``tau_ext`` (the motors are helped by it) from t = 1 s."""
    t = np.arange(int(seconds * rate)) / rate
    Q, QD, QDD = normal_motion(model, 5).evaluate(t)
    tau = rnea_batch(model, Q, QD, QDD) - np.where(t[:, None] >= 1.0, tau_ext, 0.0)
    return t, Q, QD, tau


def test_the_peaks_are_the_external_torque_the_observer_settles_on():
    model = irb140()
    tau_ext = np.array([0.0, 12.0, -5.0, 0.0, 1.5, 0.0])
    t, Q, QD, tau = recorded(model, tau_ext)
    peaks = ResidualPeaks(model)
    peaks.add(t[:700], Q[:700], QD[:700], tau[:700])
    peaks.add(t[700:], Q[700:], QD[700:], tau[700:])
    assert peaks.observed == len(t) and peaks.restarted == 0 and (peaks.start, peaks.end) == (t[0], t[-1])
    pushed = tau_ext != 0.0
    # 2 s of a 10 ms lag: settled; the unpushed joints see only the trapezoid's error of the motion
    assert peaks.peak[pushed] == pytest.approx(np.abs(tau_ext[pushed]), rel=2e-3)
    assert (peaks.peak[~pushed] < 0.05).all()
    thresholds = collision_thresholds(peaks, 2.0)
    assert thresholds == pytest.approx(2.0 * peaks.peak, rel=1e-15)


def test_samples_the_observer_cannot_take_are_left_as_id_node_leaves_them():
    model = irb140()
    t, Q, QD, tau = recorded(model, np.zeros(6), seconds=1.0)
    QD, tau, t = QD.copy(), tau.copy(), t.copy()
    QD[10:20] = np.nan  # no velocities: left out, counted
    tau[30:40] = np.nan  # no efforts: left out, the observer goes on
    tau[50, 2] = np.inf  # one effort not finite: the observer restarts
    t[300:] += 0.2  # a gap: restarts
    peaks = ResidualPeaks(model)
    peaks.add(t, Q, QD, tau)
    assert peaks.no_velocity == 10 and peaks.observed == len(t) - 21
    assert peaks.restarts == {"effort_not_finite": 1, "gap": 1}


def test_thresholds_refuse_what_they_cannot_be_set_from():
    model = irb140()
    t, Q, QD, tau = recorded(model, np.zeros(6), seconds=1.0)
    peaks = ResidualPeaks(model)
    with pytest.raises(CalibrationError, match="ran on 0 samples"):
        collision_thresholds(peaks)
    peaks.add(t, Q, QD, tau)
    with pytest.raises(CalibrationError, match="margin: must be a finite number > 1"):
        collision_thresholds(peaks, 1.0)
    still = ResidualPeaks(model)
    q = np.tile(Q[0], (50, 1))
    still.add(t[:50], q, np.zeros_like(q), rnea_batch(model, q, 0 * q, 0 * q))  # at rest, exact: r = 0
    with pytest.raises(CalibrationError, match="never left 0"):
        collision_thresholds(still)
    with pytest.raises(CalibrationError, match="observer gain"):
        ResidualPeaks(model, 0.0)
