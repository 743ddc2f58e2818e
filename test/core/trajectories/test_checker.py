"""core.trajectories.checker: a checker keeps the derived torque limits for a model of the
same joints and gravity and derives them again otherwise; a report's level follows
warn_use; its figures are the duration, the notes and one per joint and limit."""

import numpy as np

from irb140_dynamics.core import RigidBody, RobotModel, irb140
from irb140_dynamics.core.trajectories import TrajectoryChecker, check_trajectory, trajectory_limits

from ...support.trajectories import limit_use, smooth_trajectory

Q0 = np.array([0.0, -0.3, 0.5, 0.0, 0.3, 0.0])


def test_limits_kept_for_the_same_joints_and_gravity_derived_again_otherwise():
    model = irb140()
    first = TrajectoryChecker.of(model, 1000, 90.0)
    assert any("derived" in note for note in first.notes)
    again = TrajectoryChecker.of(model, 200, 50.0, first)
    assert again.limits is first.limits and again.grid == 200 and again.keeps_limits(model)
    assert first.keeps_limits(model.with_payload(RigidBody(6.0)))  # derived from the rated payload
    heavier = RobotModel.from_params({**model.to_params(), "joint_2.link.mass": 30.0})
    assert not first.keeps_limits(heavier)
    other = TrajectoryChecker.of(heavier, 1000, 90.0, first)
    assert other.limits is not first.limits
    np.testing.assert_array_equal(other.limits.torque, trajectory_limits(heavier).torque)


def test_level_headline_and_figures_of_a_report():
    model = irb140()
    tr = smooth_trajectory(model.joint_names, Q0, np.full(6, 0.3), points=50, duration=8.0)
    checker = TrajectoryChecker.of(model, 1000, 90.0)
    report = checker.check(tr)
    expected = check_trajectory(model, tr, checker.limits)
    assert [p.line() for p in report.peaks] == [p.line() for p in expected.peaks]
    use = 100 * report.worst.ratio
    assert checker.level(report) == ("ok" if use < 90.0 else "warn")
    assert TrajectoryChecker.of(model, 1000, use / 2, checker).level(report) == "warn"
    figures = checker.figures(report, ("extra",))
    assert figures[0] == ("duration [s]", f"{report.duration:.6f}") and ("note", "extra") in figures
    assert len([key for key, _ in figures if key.startswith("joint_")]) == 18
    assert report.headline().startswith(f"{report.duration:.3f} s, within every limit; worst: ")
    fast = smooth_trajectory(model.joint_names, Q0, np.full(6, 0.3), points=50, duration=0.2)
    over = checker.check(fast)
    assert checker.level(over) == "error" and "OVER A LIMIT" in over.headline()


def test_a_retimed_trajectory_keeps_the_limits():
    model = irb140()
    tr = smooth_trajectory(model.joint_names, Q0, np.full(6, 0.3), points=20, duration=8.0)
    checker = TrajectoryChecker.of(model, 300, 90.0)
    retimed, report = checker.retime(tr)
    assert retimed.duration < tr.duration and report.ok
    assert limit_use(model, retimed, checker.limits).max() <= 1.0 + 1e-6
