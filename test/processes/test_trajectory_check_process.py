"""trajectory_check_node as its own process (as `ros2 run` starts it): a trajectory sent to
the controller's topic it watches is reported on ~/trajectory_report, a bad one too (ERROR),
and it goes on."""

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus
from trajectory_msgs.msg import JointTrajectory

from irb140_dynamics.core import irb140
from irb140_dynamics.ros.messages.joint_messages import trajectory_message

from ..support.trajectories import smooth_trajectory

WATCHED = "/joint_trajectory_controller/joint_trajectory"


def test_the_watched_controller_topic_is_reported(probe, process):
    process("irb140_dynamics.nodes.trajectory_check_node.node", "-p", f"watch_topic:={WATCHED}")
    reports = []
    probe.create_subscription(DiagnosticStatus, "/trajectory_check_node/trajectory_report", reports.append, 10)
    publisher = probe.create_publisher(JointTrajectory, WATCHED, 10)
    tr = smooth_trajectory(irb140().joint_names, np.array([0.0, -0.3, 0.5, 0.0, 0.3, 0.0]), np.full(6, 0.3), 100, 10.0)
    good = trajectory_message(tr)
    probe.spin_until(lambda: publisher.get_subscription_count() > 0)
    probe.spin_until(lambda: any(r.level == DiagnosticStatus.OK for r in reports), each=lambda: publisher.publish(good))
    assert len([kv for kv in reports[-1].values if kv.key.startswith("joint_")]) == 18  # 6 joints x 3 limits

    bad = trajectory_message(tr)
    bad.joint_names[0] = "gripper"
    reports.clear()  # reports of the good ones may still come: wait for the bad one's
    probe.spin_until(
        lambda: any(r.level == DiagnosticStatus.ERROR for r in reports), each=lambda: publisher.publish(bad)
    )
    error = next(r for r in reports if r.level == DiagnosticStatus.ERROR)
    assert "unknown joint" in error.message
    reports.clear()
    probe.spin_until(lambda: any(r.level == DiagnosticStatus.OK for r in reports), each=lambda: publisher.publish(good))
