"""trajectory_check_node in-process: a report per trajectory with a KeyValue per joint and
limit, re-timed trajectories, the JTC's topic watched, bad messages answered with an ERROR
report while the node keeps running."""

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from rclpy.parameter import Parameter
from trajectory_msgs.msg import JointTrajectory

from irb140_dynamics.core import RigidBody, irb140
from irb140_dynamics.core.trajectories import check_trajectory, trajectory_limits
from irb140_dynamics.nodes.trajectory_check_node.node import TrajectoryCheckNode
from irb140_dynamics.ros.messages.joint_messages import trajectory_message, trajectory_of

from ..support.ros_harness import running
from ..support.trajectories import limit_use, smooth_trajectory

NAMES = irb140().joint_names
Q0 = np.array([0.0, -0.3, 0.5, 0.0, 0.3, 0.0])
AMPLITUDE = np.array([1.5, 0.6, 0.7, 2.0, 1.2, 2.5])
WATCHED = "/joint_trajectory_controller/joint_trajectory"


@pytest.fixture(scope="module")
def node():
    overrides = [Parameter("payload.mass", value=6.0), Parameter("watch_topic", value=WATCHED)]
    with running(TrajectoryCheckNode, parameter_overrides=overrides) as harness:
        harness.settle()  # the torque limits derived
        harness.reports = harness.listen(DiagnosticStatus, "/trajectory_check_node/trajectory_report")
        harness.retimed = harness.listen(JointTrajectory, "/trajectory_check_node/retimed")
        harness.check = harness.publisher(JointTrajectory, "/trajectory_check_node/check_trajectory")
        harness.retime = harness.publisher(JointTrajectory, "/trajectory_check_node/retime")
        harness.watched = harness.publisher(JointTrajectory, WATCHED)
        yield harness


def _report(harness, publisher, msg) -> DiagnosticStatus:
    harness.reports.clear()
    publisher.publish(msg)
    assert harness.spin_until(lambda: harness.reports), "no report"
    return harness.reports[-1]


def _message(points=100, duration=10.0, order=(3, 0, 5, 1, 4, 2)):
    tr = smooth_trajectory(NAMES, Q0, AMPLITUDE * 0.6, points=points, duration=duration)
    msg = trajectory_message(tr)
    msg.joint_names = [NAMES[i] for i in order]
    for p in msg.points:
        for field in ("positions", "velocities", "accelerations"):
            setattr(p, field, [getattr(p, field)[i] for i in order])
    return tr, msg


def test_a_report_per_trajectory_with_a_value_per_joint_and_limit(node):
    tr, msg = _message()
    status = _report(node, node.check, msg)
    model = irb140().with_payload(RigidBody(6.0))
    expected = check_trajectory(model, tr, trajectory_limits(model))
    values = {kv.key: kv.value for kv in status.values}
    for peak in expected.peaks:
        assert values[f"{peak.joint} {peak.quantity}"] == peak.line().split(": ", 1)[1]
    assert float(values["duration [s]"]) == pytest.approx(10.0)
    assert any("derived" in kv.value for kv in status.values if kv.key == "note")
    assert status.level == (DiagnosticStatus.OK if 100 * expected.worst.ratio < 90 else DiagnosticStatus.WARN)


def test_the_watched_topic_is_checked_and_too_fast_is_an_error(node):
    _, msg = _message(points=30, duration=0.5)
    status = _report(node, node.watched, msg)
    assert status.level == DiagnosticStatus.ERROR and "OVER A LIMIT" in status.message


def test_retime_publishes_the_retimed_trajectory_within_the_limits(node):
    tr, msg = _message(points=40, duration=8.0)
    node.retimed.clear()
    status = _report(node, node.retime, msg)
    assert node.spin_until(lambda: node.retimed), "no re-timed trajectory"
    model = irb140().with_payload(RigidBody(6.0))
    out = trajectory_of(node.retimed[-1], NAMES)
    assert out.duration < tr.duration and status.level != DiagnosticStatus.ERROR
    assert limit_use(model, out, trajectory_limits(model)).max() <= 1.0 + 1e-6


BAD = {
    "times": ("not after point 1", lambda m: setattr(m.points[2], "time_from_start", m.points[1].time_from_start)),
    "unknown joint": ("unknown joint", lambda m: m.joint_names.__setitem__(0, "gripper")),
    "no positions": ("point 3: no positions", lambda m: setattr(m.points[3], "positions", [])),
    "nan": ("not a finite number", lambda m: m.points[1].positions.__setitem__(2, float("nan"))),
}


@pytest.mark.parametrize("case", BAD)
def test_a_bad_message_gets_an_error_report_and_the_node_goes_on(node, case):
    reason, spoil = BAD[case]
    _, msg = _message(points=10, duration=5.0)
    spoil(msg)
    for publisher in (node.check, node.retime):
        status = _report(node, publisher, msg)
        assert status.level == DiagnosticStatus.ERROR and reason in status.message
    _, good = _message(points=10, duration=5.0)
    assert _report(node, node.check, good).level != DiagnosticStatus.ERROR  # still serving


def test_an_infeasible_path_is_refused_naming_joint_point_and_amount():
    overrides = [Parameter("payload.mass", value=60.0)]
    with running(TrajectoryCheckNode, parameter_overrides=overrides) as harness:
        harness.settle()
        reports = harness.listen(DiagnosticStatus, "/trajectory_check_node/trajectory_report")
        publisher = harness.publisher(JointTrajectory, "/trajectory_check_node/retime")
        _, msg = _message(points=10, duration=5.0)
        publisher.publish(msg)
        assert harness.spin_until(lambda: reports), "no report"
        assert reports[-1].level == DiagnosticStatus.ERROR
        assert "infeasible path: joint_" in reports[-1].message and "N m" in reports[-1].message
