"""check_trajectory: the peaks it reports are the playback's, nothing larger hides between
its samples, and the limits are the params file's or the payload check's."""

import numpy as np

from irb140_dynamics.core import RigidBody, derive_torque_limits, irb140, rnea
from irb140_dynamics.core.trajectories import Trajectory, check_trajectory, trajectory_limits
from irb140_dynamics.core.trajectories.interpolation import spline

from ...support.trajectories import smooth_trajectory, with_friction

Q0 = np.array([0.0, -0.3, 0.5, 0.0, 0.3, 0.0])
AMPLITUDE = np.array([1.5, 0.6, 0.7, 2.0, 1.2, 2.5])


def test_peaks_are_the_playbacks_and_nothing_larger_hides_between_samples():
    model = with_friction(irb140().with_payload(RigidBody(4.0)), 2.0, 3.0, 0.05)
    tr = smooth_trajectory(model.joint_names, Q0, AMPLITUDE, points=30, duration=3.0)
    report = check_trajectory(model, tr)
    sp = spline(tr)
    dense = np.linspace(0.0, sp.end, 200_001)  # 15 us apart
    q, qd, qdd = sp.evaluate(dense)
    from irb140_dynamics.core import rnea_batch

    values = {"torque": rnea_batch(model, q, qd, qdd), "velocity": qd, "acceleration": qdd}
    for peak in report.peaks:
        j = model.joint_names.index(peak.joint)
        densest = np.abs(values[peak.quantity][:, j]).max()
        assert abs(peak.value) <= densest * (1 + 1e-9) + 1e-12  # a value the playback takes
        assert densest <= abs(peak.value) * (1 + 1e-6) + 1e-9  # and none larger
        if peak.quantity == "torque":  # at the time reported
            k = sp.segment_of(np.array([peak.time]))
            state = [x[0] for x in sp.evaluate(np.array([peak.time]), k)]
            assert np.isclose(rnea(model, *state)[j], peak.value, rtol=1e-9)
            assert 0 <= peak.point < len(tr.t)


def test_torque_limits_of_zero_are_the_payload_checks():
    model = irb140()
    limits = trajectory_limits(model)
    derived = derive_torque_limits(model)
    np.testing.assert_array_equal(limits.torque, derived.values)
    assert limits.torque_source == derived.source and "derived" in limits.torque_source
    np.testing.assert_array_equal(limits.velocity, [j.velocity_limit for j in model.joints])


def test_a_pose_held_over_a_torque_limit_is_found_with_its_joint_and_point():
    model = irb140().with_payload(RigidBody(30.0))
    q = np.tile(np.array([0.0, -1.2, 1.0, 0.0, 0.5, 0.0]), (3, 1))
    q[2, 0] = 0.3
    tr = Trajectory.of(model.joint_names, [0.0, 1.0, 2.0], q, np.zeros_like(q))  # cubic, at rest at points
    report = check_trajectory(model, tr)
    worst = report.worst
    assert not report.ok and worst.quantity == "torque"
    j = model.joint_names.index(worst.joint)
    held = abs(rnea(model, q[0], np.zeros(6), np.zeros(6))[j])
    assert held > trajectory_limits(model).torque[j]
    assert abs(worst.value) >= held * (1 - 1e-9)


def test_a_velocity_step_at_a_point_needs_an_unbounded_acceleration():
    model = irb140()
    q = np.zeros((3, 6))
    q[1, 0], q[2, 1] = 0.5, 0.5  # a corner at point 1, positions only: linear segments
    report = check_trajectory(model, Trajectory.of(model.joint_names, [0.0, 1.0, 2.0], q))
    accelerations = [p for p in report.peaks if p.quantity == "acceleration" and not np.isfinite(p.value)]
    assert accelerations and accelerations[0].point == 1 and not report.ok
