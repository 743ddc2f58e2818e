"""id_node itself with the parameter file calibrate_collision wrote: started with the arm's
file and it (``--params-file`` twice, as docs/id_node.md says), fed a pushed recording of
the simulated IRB-140 message by message, it raises `collision` within 20 ms of each push's
first joint state and not before. (The 60 s without alarm and the pushes in every
direction, with the observer run as id_node runs it: test/tools/test_calibrate_collision_sim.py.)"""

import contextlib
import io
import re

import numpy as np
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool

from irb140_dynamics.core.io.params_file import load_model, read_parameter_file
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.tools import calibrate_collision

from ..support.collision_harness import feed
from ..support.paths import ROOT
from ..support.ros_harness import running
from ..support.simulated_pushes import Push, normal_motion, run, write_csv

ARM = ROOT / "config" / "true_arm.yaml"
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


def test_id_node_with_the_written_thresholds_flags_pushes_within_20_ms(tmp_path):
    arm = load_model(ARM)
    motion = normal_motion(arm, 1)
    recording = write_csv(tmp_path / "normal.csv", arm.joint_names, *run(arm, motion, 10.0, seed=1))
    out = tmp_path / "collision.yaml"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert calibrate_collision.main(["--params-file", str(ARM), str(recording), "--out", str(out), "--quiet"]) == 0
    figure = {
        a: float(re.search(rf"^{re.escape(a)}: (\S+) N", printed.getvalue(), re.M).group(1)) for a in ("+x", "-z")
    }
    pushes = [
        Push(0.5, 0.7, np.array([1.5 * figure["+x"], 0.0, 0.0])),
        Push(1.0, 1.2, np.array([0.0, 0.0, -1.5 * figure["-z"]])),
    ]
    t, Q, QD, TAU = run(arm, motion, 1.3, seed=3, pushes=pushes)
    assert read_parameter_file(out)["collision.observer_gain"] == 100.0
    cli = ["--ros-args", "--params-file", str(ARM), "--params-file", str(out)]
    with running(IdNode, cli_args=cli) as harness:
        assert harness.spin_until(lambda: harness.node.settings is not None), "no model"
        flags = harness.listen(Bool, "collision", LATCHED)
        harness.external = harness.listen(JointState, "external_torques")
        harness.gravity = harness.listen(JointState, "gravity_torques")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        thresholds = harness.node.settings.collision.thresholds
        assert thresholds.tolist() == [read_parameter_file(out)[f"{n}.collision_threshold"] for n in arm.joint_names]
        colliding = []
        for k in range(len(t)):
            feed(harness, t[k], Q[k], QD[k], TAU[k])
            colliding.append(bool(harness.node.collision.colliding))
        assert harness.spin_until(lambda: len(flags) >= 2)
    colliding = np.array(colliding)
    for push in pushes:
        first = int(np.searchsorted(t, push.start - 1e-9))
        assert not colliding[first - 100 : first].any()  # 0.2 s before: none
        hit = np.flatnonzero(colliding[first:])
        assert len(hit) and t[first + hit[0]] - t[first] <= 0.020, (push, hit[:3])
    assert not colliding[: int(np.searchsorted(t, pushes[0].start))].any()  # nothing before the first push
    assert any(flag.data for flag in flags)
