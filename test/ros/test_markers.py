"""id_node's markers: colours, labels and positions against the model (forward kinematics as
Pinocchio's, |tau|/limit with the payload check's limits), the frame the URDF's base link;
in-process: none before a joint state, the arrow and the collision text from efforts."""

import numpy as np
import pinocchio as pin
import pytest
from builtin_interfaces.msg import Time
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from visualization_msgs.msg import Marker, MarkerArray

from irb140_dynamics.core import RigidBody, derive_torque_limits, gravity, irb140
from irb140_dynamics.core.io.urdf import export_urdf, load_urdf
from irb140_dynamics.core.kinematics import flange_pose
from irb140_dynamics.core.monitoring import display
from irb140_dynamics.core.monitoring.wrench import flange_jacobian_in
from irb140_dynamics.nodes.id_node.markers import MarkerScene, build_markers, lifetime
from irb140_dynamics.nodes.id_node.node import IdNode

from ..support.ros_harness import running
from ..support.urdf_support import pinocchio_of

PAYLOAD = RigidBody(3.0, (0.0, 0.02, 0.05))
MODEL = irb140(payload=PAYLOAD)
Q = np.array([0.3, -0.4, 0.5, 0.2, 0.7, 0.1])
F_BASE = np.array([5.0, -20.0, 10.0, 0.0, 0.0, 0.0])  # N: on the flange, base axes


def by_key(markers: MarkerArray) -> dict:
    keys = [(m.ns, m.id) for m in markers.markers]
    assert len(keys) == len(set(keys)), "namespaces and ids must be unique"
    return {(m.ns, m.id): m for m in markers.markers}


def xyz(point) -> np.ndarray:
    return np.array([point.x, point.y, point.z])


def rgb(marker) -> tuple:
    return (marker.color.r, marker.color.g, marker.color.b)


@pytest.fixture(scope="module")
def limits():
    return np.array(derive_torque_limits(MODEL).values)


def scene(limits, tau, external=None, colliding=()):
    return by_key(build_markers(MODEL, limits, "base_link", Time(sec=7, nanosec=5), Q, tau, external, colliding, 0.3))


def test_joint_spheres_sit_on_the_joints_coloured_by_load(limits):
    # joint 1 has no limit (gravity cannot load it: grey); joint 3 at 81 %; joint 2 at 50 %
    tau = np.array([12.0, -0.5 * limits[1], 0.81 * limits[2], 0.0, 1.2 * limits[4], 0.5])
    markers = scene(limits, tau)
    pm = pinocchio_of(export_urdf(MODEL))  # its own parser, frames and kinematics
    data = pm.createData()
    pin.forwardKinematics(pm, data, Q)
    names = MODEL.joint_names
    for j, name in enumerate(names):
        sphere, label = markers[("joint_load", j)], markers[("joint_label", j)]
        assert sphere.type == Marker.SPHERE and label.type == Marker.TEXT_VIEW_FACING
        origin = data.oMi[pm.getJointId(name)].translation
        np.testing.assert_allclose(xyz(sphere.pose.position), origin, atol=1e-9)
        assert xyz(label.pose.position)[2] > origin[2]
    assert rgb(markers[("joint_load", 0)]) == pytest.approx(display.GREY)
    assert markers[("joint_label", 0)].text == "joint_1 (12.0 N m, no limit)"
    assert rgb(markers[("joint_load", 1)]) == pytest.approx((0.5 / 0.7, 1.0, 0.0))  # green to yellow
    assert rgb(markers[("joint_load", 2)]) == pytest.approx((1.0, 1.0 - 0.11 / 0.3, 0.0))  # yellow to red
    assert markers[("joint_label", 2)].text == f"joint_3 81 % ({0.81 * limits[2]:.1f} N m)"
    assert rgb(markers[("joint_load", 3)]) == pytest.approx(display.GREEN)
    assert rgb(markers[("joint_load", 4)]) == pytest.approx(display.RED)  # beyond its limit
    assert markers[("joint_label", 4)].text == "joint_5 120 % (7.5 N m)"


def test_payload_arrow_collision_frames_and_lifetime(limits):
    J = flange_jacobian_in(MODEL, Q, "base")
    markers = scene(limits, gravity(MODEL, Q), external=J.T @ F_BASE, colliding=["joint_2", "joint_3"])
    pose = flange_pose(MODEL, Q)
    payload = markers[("payload", 0)]
    np.testing.assert_allclose(xyz(payload.pose.position), pose[:3, :3] @ PAYLOAD.com + pose[:3, 3], atol=1e-12)
    assert payload.scale.x == pytest.approx(display.payload_diameter(3.0))
    arrow = markers[("external_force", 0)]
    assert arrow.type == Marker.ARROW
    np.testing.assert_allclose(xyz(arrow.points[0]), pose[:3, 3], atol=1e-12)
    np.testing.assert_allclose(xyz(arrow.points[1]) - xyz(arrow.points[0]), 0.01 * F_BASE[:3], atol=1e-9)
    assert markers[("external_force", 1)].text == f"{np.linalg.norm(F_BASE[:3]):.1f} N"
    collision = markers[("collision", 0)]
    assert collision.text == "collision: joint_2, joint_3" and rgb(collision) == (1.0, 0.0, 0.0)
    urdf_base = load_urdf(export_urdf(MODEL)).base_link  # the root link export_urdf writes
    for marker in markers.values():
        assert marker.header.frame_id == urdf_base
        if marker.action == Marker.ADD:
            assert (marker.header.stamp.sec, marker.header.stamp.nanosec) == (7, 5)
            assert (marker.lifetime.sec, marker.lifetime.nanosec) == (0, 300_000_000)


def test_without_efforts_or_collision_their_markers_are_deleted(limits):
    markers = scene(limits, np.zeros(6))
    for key in (("external_force", 0), ("external_force", 1), ("collision", 0)):
        assert markers[key].action == Marker.DELETE


def test_a_scene_kept_between_states_publishes_what_a_fresh_build_does(limits):
    # the node keeps one scene per model and frame: arrows, collision texts and limits come
    # and go between states; each update must equal the markers built afresh, nothing stale
    kept = MarkerScene(MODEL, "base_link", 0.3)
    rng = np.random.default_rng(5)
    for i in range(12):
        q, tau = rng.uniform(-2.0, 2.0, 6), rng.uniform(-200.0, 200.0, 6)
        external = rng.uniform(-30.0, 30.0, 6) if i % 3 else None
        colliding, shown = ("joint_2", "joint_3")[: i % 3], None if i % 4 == 0 else limits
        stamp = Time(sec=i, nanosec=1000 * i)
        fresh = build_markers(MODEL, shown, "base_link", stamp, q, tau, external, colliding, 0.3)
        assert kept.update(shown, stamp, q, tau, external, colliding) == fresh, f"state {i}"
    with pytest.raises(ValueError):  # refused; the next state is drawn whole again
        kept.update(limits, Time(), [np.nan] * 6, np.zeros(6))
    assert kept.update(shown, stamp, q, tau, external, colliding) == fresh


def test_lifetime_spans_three_periods():
    assert lifetime(10.0) == pytest.approx(0.5) and lifetime(1.0) == 3.0 and lifetime(100.0) == 0.5


def test_nothing_is_finite_or_published_from_a_bad_state(limits):
    with pytest.raises(ValueError):
        build_markers(MODEL, limits, "base_link", Time(), [np.nan] * 6, np.zeros(6))


def test_the_node_publishes_markers_after_joint_states_only():
    overrides = [
        Parameter("markers.rate", value=20.0),
        Parameter("payload.mass", value=3.0),
        Parameter("joint_2.collision_threshold", value=5.0),
    ]
    with running(IdNode, parameter_overrides=overrides) as harness:
        markers = harness.listen(MarkerArray, "/id_node/markers")
        states = harness.publisher(JointState, "joint_states")
        harness.spin_for(0.5)
        assert markers == []  # no joint state yet
        g = gravity(irb140(payload=RigidBody(3.0)), Q)
        push = np.array([0.0, 20.0, 0.0, 0.0, 0.0, 0.0])  # N m on joint 2: over its threshold
        for k in range(80):
            msg = JointState(name=list(MODEL.joint_names), position=Q.tolist(), velocity=[0.0] * 6)
            msg.effort = (g - push).tolist()
            msg.header.stamp.sec, msg.header.stamp.nanosec = 5, k * 1_000_000
            states.publish(msg)
            harness.spin_for(0.002)
        colliding = lambda: markers and by_key(markers[-1])[("collision", 0)].action == Marker.ADD  # noqa: E731
        assert harness.spin_until(colliding)
        last = by_key(markers[-1])
    assert last[("collision", 0)].text == "collision: joint_2"
    assert last[("external_force", 0)].action == Marker.ADD
    assert {m.header.frame_id for m in last.values()} == {"base_link"}


def test_no_markers_are_built_while_nobody_subscribes():
    with running(IdNode, parameter_overrides=[Parameter("markers.rate", value=50.0)]) as harness:
        torques = harness.listen(JointState, "feedforward_torques")
        states = harness.publisher(JointState, "joint_states")
        msg = JointState(name=list(MODEL.joint_names), position=Q.tolist(), velocity=[0.0] * 6)
        states.publish(msg)
        assert harness.spin_until(lambda: torques)
        harness.spin_for(0.3)  # 15 ticks of the markers' timer
        assert harness.node.markers.published == 0
        markers = harness.listen(MarkerArray, "/id_node/markers")
        states.publish(msg)  # the last joint state's markers go to the subscriber once it is matched
        assert harness.spin_until(lambda: markers)
    assert harness.node.markers.published >= 1
    assert {m.ns for m in markers[-1].markers} >= {"joint_load", "joint_label"}


def test_a_urdf_arm_s_markers_are_in_its_base_link():
    from ..support.urdf_support import ARMS, arm_text

    overrides = [
        Parameter("model.source", value="robot_description"),
        Parameter("model.tip_link", value=ARMS["ur5"][1]),
        Parameter("robot_description", value=arm_text("ur5")),
        Parameter("markers.rate", value=20.0),
    ]
    with running(IdNode, parameter_overrides=overrides) as harness:
        markers = harness.listen(MarkerArray, "/id_node/markers")
        states = harness.publisher(JointState, "joint_states")
        names = list(harness.node.settings.model.joint_names)
        states.publish(JointState(name=names, position=[0.1] * 6, velocity=[0.0] * 6))
        assert harness.spin_until(lambda: markers)
    assert {m.header.frame_id for m in markers[-1].markers} == {"world"}  # the UR5 URDF's root link
    labels = [m.text for m in markers[-1].markers if m.ns == "joint_label"]
    assert [label.split()[0] for label in labels] == names and all("%" in label for label in labels)  # given limits


def test_the_rated_payload_sets_the_limits_the_joints_are_coloured_by():
    """rated_payload.mass (and .com) derive the markers' limits for joints without
    torque_limit, as the payload check does; a change at runtime re-derives them; a bad
    CoM is refused and the old limits stay."""
    arm = irb140()
    tau = gravity(arm, Q)  # the feed-forward torque at rest (no efforts in the joint states)

    def expected(mass):
        limit = derive_torque_limits(arm, RigidBody(mass)).values[4]
        return f"joint_5 {100.0 * abs(tau[4]) / limit:.0f} % ({abs(tau[4]):.1f} N m)"

    overrides = [Parameter("markers.rate", value=50.0), Parameter("rated_payload.mass", value=1.0)]
    with running(IdNode, parameter_overrides=overrides) as harness:
        markers = harness.listen(MarkerArray, "/id_node/markers")
        states = harness.publisher(JointState, "joint_states")

        def label():
            states.publish(JointState(name=list(arm.joint_names), position=Q.tolist(), velocity=[0.0] * 6))
            harness.spin_for(0.05)
            return markers and by_key(markers[-1])[("joint_label", 4)].text

        assert harness.spin_until(lambda: label() == expected(1.0)), markers and label()
        assert harness.set_parameters([Parameter("rated_payload.mass", value=6.0)])[0].successful
        assert harness.spin_until(lambda: label() == expected(6.0)), label()
        refused = harness.set_parameters([Parameter("rated_payload.com", value=[0.0, float("nan"), 0.0])])[0]
        assert not refused.successful and "rated_payload" in refused.reason
        assert label() == expected(6.0)
    assert expected(1.0) != expected(6.0)
