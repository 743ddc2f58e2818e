"""id_node in-process with real rclpy and DDS: torques, reference, parameters, bad input."""

import math

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from irb140_dynamics.core import RobotModel, gravity, irb140, rnea
from irb140_dynamics.nodes.id_node.node import IdNode

from ..support.ros_harness import running

NAMES = [f"joint_{i}" for i in range(1, 7)]
STRETCHED = [0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0]
ZERO_ACCELERATION = [Parameter("acceleration.mode", value="zero")]


def joint_state(q, qd=(), names=NAMES, sec=1, nanosec=0):
    msg = JointState(name=list(names), position=[float(x) for x in q], velocity=[float(x) for x in qd])
    msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
    return msg


def shuffled_with_extras(q, qd, rng):
    """The same state with the joints in a random order and two joints the model lacks."""
    names = NAMES + ["gripper_left", "gripper_right"]
    q, qd = list(q) + [0.01, 0.02], list(qd) + [0.3, -0.3]
    order = rng.permutation(len(names))
    return joint_state([q[i] for i in order], [qd[i] for i in order], [names[i] for i in order])


@pytest.fixture
def node():
    with running(IdNode, parameter_overrides=ZERO_ACCELERATION) as harness:
        harness.feedforward = harness.listen(JointState, "feedforward_torques")
        harness.gravity = harness.listen(JointState, "gravity_torques")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        yield harness


def send(harness, msg, expect=1):
    """Publish one joint state and wait for ``expect`` new torque messages on each topic."""
    ff, g = len(harness.feedforward), len(harness.gravity)
    received = harness.node.counts["joint_states.received"]
    harness.joint_states.publish(msg)
    if expect:
        assert harness.spin_until(
            lambda: len(harness.feedforward) >= ff + expect and len(harness.gravity) >= g + expect
        )
        return harness.feedforward[-1], harness.gravity[-1]
    assert harness.spin_until(lambda: harness.node.counts["joint_states.received"] > received)  # it was read
    harness.spin_for(0.3)
    assert (len(harness.feedforward), len(harness.gravity)) == (ff, g), "a bad message yielded torques"
    return None


def test_report_torques_at_the_stretched_pose(node):
    ff, g = send(node, joint_state(STRETCHED, sec=7, nanosec=5))
    assert ff.name == NAMES and g.name == NAMES
    np.testing.assert_allclose(g.effort, [0, 243.382, 79.1556, 0, 2.43004, 0], atol=1e-3)
    np.testing.assert_allclose(ff.effort, g.effort, atol=1e-12)
    assert (g.header.stamp.sec, g.header.stamp.nanosec) == (7, 5)
    assert (ff.header.stamp.sec, ff.header.stamp.nanosec) == (7, 5)


def test_torques_match_the_core_by_name_in_any_order(node):
    rng = np.random.default_rng(3)
    model = irb140()
    for _ in range(5):
        q, qd = rng.uniform(-2, 2, 6), rng.uniform(-1, 1, 6)
        ff, g = send(node, shuffled_with_extras(q, qd, rng))
        np.testing.assert_allclose(ff.effort, rnea(model, q, qd, np.zeros(6)), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(g.effort, gravity(model, q), rtol=1e-12, atol=1e-12)


def test_unnamed_message_of_the_right_length_is_positional(node):
    q = [0.1, -0.4, 0.8, 0.2, -0.3, 0.5]
    _, g = send(node, joint_state(q, names=[]))
    np.testing.assert_allclose(g.effort, gravity(irb140(), q), rtol=1e-12, atol=1e-12)


def test_missing_velocities_count_as_zero(node):
    q = [0.3, -0.2, 0.4, 0.0, 0.9, -0.1]
    ff, _ = send(node, joint_state(q))
    np.testing.assert_allclose(ff.effort, rnea(irb140(), q, np.zeros(6), np.zeros(6)), rtol=1e-12, atol=1e-12)


def test_reference_gives_exact_feedforward(node):
    reference = node.publisher(JointTrajectory, "/id_node/reference")
    q_ref, qd_ref, qdd_ref = (
        [0.2, -1.0, 1.2, 0.3, 0.4, 0.5],
        [0.5, -0.2, 0.3, 1.0, -0.5, 0.2],
        [1.0, 2.0, -3.0, 4.0, -5.0, 6.0],
    )
    order = [3, 0, 5, 1, 4, 2]
    point = JointTrajectoryPoint(
        positions=[q_ref[i] for i in order],
        velocities=[qd_ref[i] for i in order],
        accelerations=[qdd_ref[i] for i in order],
    )
    reference.publish(JointTrajectory(joint_names=[NAMES[i] for i in order], points=[point]))
    assert node.spin_until(lambda: node.node.stream.tracker.trajectory is not None)
    q_measured = [0.0, -0.5, 0.5, 0.0, 0.0, 0.0]
    ff, g = send(node, joint_state(q_measured))
    np.testing.assert_allclose(ff.effort, rnea(irb140(), q_ref, qd_ref, qdd_ref), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(g.effort, gravity(irb140(), q_measured), rtol=1e-12, atol=1e-12)


def test_valid_runtime_changes_apply_to_the_next_message(node):
    changes = {"payload.mass": 4.0, "joint_2.link.mass": 30.0, "gravity": [0.0, 0.0, -9.80665]}
    for name, value in changes.items():
        assert [r.successful for r in node.set_parameters([Parameter(name, value=value)])] == [True]
    expected = RobotModel.from_params(irb140().to_params() | changes)
    q = [0.1, -1.1, 1.4, 0.2, 0.7, 0.0]
    _, g = send(node, joint_state(q))
    np.testing.assert_allclose(g.effort, gravity(expected, q), rtol=1e-12, atol=1e-12)
    assert not np.allclose(g.effort, gravity(irb140(), q))


@pytest.mark.parametrize(
    "parameter, reason",
    [
        (Parameter("joint_3.link.inertia", value=[1.0, -1.0, 1.0, 0.0, 0.0, 0.0]), "joint_3.link.inertia"),
        (Parameter("joint_2.link.com", value=[0.0, 1.0]), "joint_2.link.com: expected 3 numbers"),
        (Parameter("gravity", value=[0.0, math.nan, -9.81]), "gravity: must be finite"),
        (Parameter("payload.inertia", value=[1.0, 1.0, 5.0, 0.0, 0.0, 0.0]), "triangle inequality"),
        (Parameter("joint_1.position_limits", value=[1.0, -1.0]), "joint_1.position_limits"),
        (Parameter("payload.mass", value=-1.0), "payload.mass"),
        (Parameter("acceleration.mode", value="guess"), "acceleration.mode"),
        (Parameter("joint_names", value=["a", "b"]), "read-only"),
    ],
)
def test_invalid_change_is_refused_with_its_reason_and_changes_nothing(node, parameter, reason):
    before = node.node.settings
    [result] = node.set_parameters([parameter])
    assert not result.successful
    assert reason in result.reason
    assert node.node.settings is before
    _, g = send(node, joint_state(STRETCHED))
    np.testing.assert_allclose(g.effort, [0, 243.382, 79.1556, 0, 2.43004, 0], atol=1e-3)


def test_atomic_set_applies_all_or_none(node):
    good = Parameter("payload.mass", value=6.0)
    bad = Parameter("joint_4.link.mass", value=-3.0)
    result = node.set_parameters_atomically([good, bad])
    assert not result.successful
    assert node.node.get_parameter("payload.mass").value == 0.0
    _, g = send(node, joint_state(STRETCHED))
    np.testing.assert_allclose(g.effort, [0, 243.382, 79.1556, 0, 2.43004, 0], atol=1e-3)

    result = node.set_parameters_atomically([good, Parameter("joint_4.link.mass", value=25.920256)])
    assert result.successful
    _, g = send(node, joint_state(STRETCHED))
    np.testing.assert_allclose(g.effort, [0, 290.765, 105.348, 0, 6.25594, 0], atol=1e-3)


@pytest.mark.parametrize(
    "msg, kind",
    [
        (joint_state([0.0, math.nan, 0.0, 0.0, 0.0, 0.0]), "not_finite"),
        (joint_state([0.0, math.inf, 0.0, 0.0, 0.0, 0.0]), "not_finite"),
        (joint_state(STRETCHED, qd=[0.0, 0.0, -math.inf, 0.0, 0.0, 0.0]), "not_finite"),
        (joint_state(STRETCHED[:5], names=NAMES), "length_mismatch"),
        (joint_state(STRETCHED, qd=[0.0, 0.0]), "length_mismatch"),
        (joint_state(STRETCHED, names=NAMES[:5] + ["joint_5"]), "duplicate_names"),
        (joint_state(STRETCHED[:5], names=NAMES[:5]), "missing_joints"),
        (joint_state(STRETCHED[:5], names=[]), "unnamed"),
        (JointState(name=NAMES, position=STRETCHED, effort=[1.0, 2.0]), "length_mismatch"),
        (joint_state(STRETCHED, qd=[1e200] * 6), "non_finite_torques"),
    ],
)
def test_bad_message_is_dropped_and_counted(node, msg, kind):
    send(node, msg, expect=0)
    assert node.node.counts[f"joint_states.dropped_{kind}"] == 1
    _, g = send(node, joint_state(STRETCHED))  # still alive and right
    np.testing.assert_allclose(g.effort, [0, 243.382, 79.1556, 0, 2.43004, 0], atol=1e-3)


def test_undecodable_bytes_on_joint_states_are_dropped_as_malformed(node):
    """A publisher may send any bytes under the JointState type (rclpy's publish(bytes)):
    id_node reads them itself (core.io.joint_state_cdr), drops them, and goes on."""
    garbage = [
        b"",
        b"\x00\x01\x00\x00",
        b"\x00\x01\x00\x00" + b"\xff" * 40,  # a count of 4e9 names
        b"\x00\x00\x00\x00" + b"\x07" * 30,
        b"\x13\x37" * 50,
    ]  # big-endian (rclpy's reader), unknown
    for raw in garbage:
        send(node, raw, expect=0)
    assert node.node.counts["joint_states.dropped_malformed"] == len(garbage)
    assert not any(key.endswith(".errors") for key in node.node.counts), dict(node.node.counts)
    _, g = send(node, joint_state(STRETCHED))  # still alive and right
    np.testing.assert_allclose(g.effort, [0, 243.382, 79.1556, 0, 2.43004, 0], atol=1e-3)


@pytest.mark.parametrize("reliability", [ReliabilityPolicy.RELIABLE, ReliabilityPolicy.BEST_EFFORT])
def test_reliable_and_best_effort_publishers_are_both_heard(node, reliability):
    pub = node.publisher(JointState, "joint_states", QoSProfile(depth=10, reliability=reliability))
    node.joint_states = pub
    _, g = send(node, joint_state(STRETCHED))
    np.testing.assert_allclose(g.effort, [0, 243.382, 79.1556, 0, 2.43004, 0], atol=1e-3)


def test_differentiated_acceleration_converges_on_a_velocity_ramp():
    qdd_true = np.array([0.5, -1.0, 2.0, 0.0, 1.5, -0.5])
    overrides = [
        Parameter("acceleration.mode", value="differentiate"),
        Parameter("acceleration.cutoff_frequency", value=50.0),
    ]
    with running(IdNode, parameter_overrides=overrides) as harness:
        feedforward = harness.listen(JointState, "feedforward_torques")
        pub = harness.publisher(JointState, "joint_states")
        q = np.array([0.1, -0.8, 1.0, 0.0, 0.5, 0.0])
        dt = 0.002
        for k in range(100):
            t = 1.0 + k * dt
            qd = qdd_true * (t - 1.0)
            pub.publish(joint_state(q, qd, sec=int(t), nanosec=int(round((t % 1) * 1e9))))
            assert harness.spin_until(lambda: len(feedforward) > k)
        expected = rnea(irb140(), q, qd, qdd_true)
        np.testing.assert_allclose(feedforward[-1].effort, expected, rtol=1e-6, atol=1e-6)


def test_effort_commands_carry_the_feedforward_in_model_order():
    overrides = ZERO_ACCELERATION + [Parameter("effort_commands.enabled", value=True)]
    with running(IdNode, parameter_overrides=overrides) as harness:
        commands = harness.listen(Float64MultiArray, "effort_commands")
        pub = harness.publisher(JointState, "joint_states")
        q, qd = [0.2, -1.0, 1.1, 0.4, -0.6, 0.3], [0.1, 0.2, -0.3, 0.4, 0.5, -0.6]
        pub.publish(joint_state(q, qd))
        assert harness.spin_until(lambda: commands)
        np.testing.assert_allclose(commands[0].data, rnea(irb140(), q, qd, np.zeros(6)), rtol=1e-12, atol=1e-12)


def test_messages_about_other_joints_only_are_ignored_quietly(node):
    gripper = JointState(name=["gripper_left", "gripper_right"], position=[0.01, 0.01])
    send(node, gripper, expect=0)
    assert node.node.counts["joint_states.ignored"] == 1 and node.node.counts["joint_states.dropped"] == 0
    msg = joint_state(STRETCHED)
    msg.effort = [math.nan] * 6  # effort is not used: its values do not matter
    _, g = send(node, msg)
    np.testing.assert_allclose(g.effort, [0, 243.382, 79.1556, 0, 2.43004, 0], atol=1e-3)


def reference_point(q, qd=(), qdd=()):
    return JointTrajectory(
        joint_names=NAMES,
        points=[JointTrajectoryPoint(positions=list(q), velocities=list(qd), accelerations=list(qdd))],
    )


def test_reference_expires_and_an_empty_one_lets_it_go():
    overrides = [Parameter("reference_timeout", value=1.0)]  # a stall shorter than this changes nothing
    with running(IdNode, parameter_overrides=overrides) as harness:
        harness.feedforward = harness.listen(JointState, "feedforward_torques")
        harness.gravity = harness.listen(JointState, "gravity_torques")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        reference = harness.publisher(JointTrajectory, "/id_node/reference")
        model, zeros = irb140(), np.zeros(6)
        q_ref, q = [0.3, -0.9, 1.1, 0.0, 0.4, 0.0], [0.0, -0.5, 0.5, 0.0, 0.0, 0.0]
        for clear in (False, True):
            harness.node.stream.tracker.clear()
            reference.publish(reference_point(q_ref))  # no accelerations given: qdd = 0 (mode zero)
            assert harness.spin_until(lambda: harness.node.stream.tracker.trajectory is not None)
            ff, _ = send(harness, joint_state(q))
            np.testing.assert_allclose(ff.effort, rnea(model, q_ref, zeros, zeros), rtol=1e-12, atol=1e-12)
            if clear:
                reference.publish(JointTrajectory())
                assert harness.spin_until(lambda: harness.node.stream.tracker.trajectory is None)
            else:  # until the node's clock is past the timeout (its reference let go)
                node = harness.node
                assert harness.spin_until(
                    lambda: node.stream.tracker.sample(node.get_clock().now().nanoseconds * 1e-9, 1.0) is None
                )
            ff, _ = send(harness, joint_state(q))
            np.testing.assert_allclose(ff.effort, rnea(model, q, zeros, zeros), rtol=1e-12, atol=1e-12)


def test_a_bad_reference_is_dropped_and_the_held_one_kept(node):
    reference = node.publisher(JointTrajectory, "/id_node/reference")
    q_ref = [0.3, -0.9, 1.1, 0.0, 0.4, 0.0]
    reference.publish(reference_point(q_ref))
    assert node.spin_until(lambda: node.node.stream.tracker.trajectory is not None)
    reference.publish(JointTrajectory(joint_names=NAMES[:5], points=[JointTrajectoryPoint(positions=[0.0] * 5)]))
    assert node.spin_until(lambda: node.node.counts["reference.dropped_missing_joints"] == 1)
    ff, _ = send(node, joint_state(STRETCHED))
    np.testing.assert_allclose(ff.effort, rnea(irb140(), q_ref, np.zeros(6), np.zeros(6)), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize(
    "mode, source, expected",
    [
        ("zero", "gravity", lambda q, qd: gravity(irb140(), q)),
        # a measured acceleration never reaches a command: it would feed the arm's own motion back
        ("differentiate", "feedforward", lambda q, qd: rnea(irb140(), q, qd, np.zeros(6))),
    ],
)
def test_effort_commands_sources(mode, source, expected):
    overrides = [
        Parameter("effort_commands.enabled", value=True),
        Parameter("acceleration.mode", value=mode),
        Parameter("effort_commands.source", value=source),
    ]
    with running(IdNode, parameter_overrides=overrides) as harness:
        commands = harness.listen(Float64MultiArray, "effort_commands")
        feedforward = harness.listen(JointState, "feedforward_torques")
        pub = harness.publisher(JointState, "joint_states")
        q = np.array([0.2, -1.0, 1.1, 0.4, -0.6, 0.3])
        for k in range(5):  # accelerating, so that a differentiated qdd is not zero
            qd = 2.0 * k * 0.01 * np.ones(6)
            pub.publish(joint_state(q, qd, sec=1, nanosec=k * 10_000_000))
            assert harness.spin_until(lambda: len(commands) > k and len(feedforward) > k)
        np.testing.assert_allclose(commands[-1].data, expected(q, qd), rtol=1e-12, atol=1e-12)
        if mode == "differentiate":
            assert not np.allclose(feedforward[-1].effort, commands[-1].data)


def test_reliable_subscription_when_asked():
    overrides = [Parameter("qos.reliability", value="reliable")]
    with running(IdNode, parameter_overrides=overrides) as harness:
        gravity_torques = harness.listen(JointState, "gravity_torques")
        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        harness.publisher(JointState, "joint_states", reliable).publish(joint_state(STRETCHED))
        assert harness.spin_until(lambda: gravity_torques)
        assert harness.node.get_parameter("qos.reliability").value == "reliable"


def test_diagnostics_warn_about_dropped_messages(node):
    diagnostics = node.listen(DiagnosticArray, "/diagnostics")
    send(node, joint_state([math.nan] * 6), expect=0)

    def warned():
        return any(s.level == DiagnosticStatus.WARN for d in diagnostics for s in d.status)

    assert node.spin_until(warned)
    status = [s for d in diagnostics for s in d.status if s.level == DiagnosticStatus.WARN][0]
    assert status.name == "id_node: messages" and "dropped" in status.message
    assert {kv.key: kv.value for kv in status.values}["joint_states.dropped_not_finite"] == "1"
