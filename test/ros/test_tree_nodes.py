"""id_node and sim_node on a whole kinematic tree, in-process: Baxter (test/data/urdf: two arms,
a head pan, grippers whose second finger is a mimic joint), read with no tip_link. Its gravity
and feed-forward torques of every independent joint, by name, against Pinocchio's of the same
tree (test.support.pinocchio_trees), from one JointState naming the joints in any order, mimic
joints among them (ignored); a payload on a named link; the markers; the external torques.
sim_node on a tree (test_urdf_trees' TWO_ARMS without its mimic joints; Baxter with its)."""

import numpy as np
import pinocchio as pin
import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import WrenchStamped
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from irb140_dynamics.core import RigidBody, gravity, rnea
from irb140_dynamics.core.io.arm_source import UrdfText, read_arm
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.monitoring.link_wrenches import SINGULAR_THRESHOLD, link_wrenches, wrench_places
from irb140_dynamics.core.monitoring.wrench import TREE_REFUSAL, WrenchStream
from irb140_dynamics.nodes.id_node.markers import build_markers
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode
from irb140_dynamics.nodes.sim_node.node import SimNode

from ..core.test_urdf_trees import TWO_ARMS, _without_mimics
from ..support.paths import URDF_DATA
from ..support.pinocchio_model import spatial_inertia
from ..support.pinocchio_trees import pinocchio_of, pinocchio_state, reference
from ..support.ros_harness import running
from .test_sim_node import states_after_reset

PAYLOAD = RigidBody(2.0, (0.01, -0.02, 0.08), (0.01, 0.02, 0.015, 0.001, 0.0, -0.002))


BAXTER = (URDF_DATA / "baxter.urdf").read_text()  # example-robot-data 6.0.0's, unchanged


def from_description(**values):
    overrides = [Parameter("model.source", value="robot_description"), Parameter("robot_description", value=BAXTER)]
    return overrides + [Parameter(name.replace("__", "."), value=value) for name, value in values.items()]


def answers(harness, names, q, qd):
    """Publish one joint state; the (gravity_torques, feedforward_torques) messages it yields."""
    topics = ("gravity_torques", "feedforward_torques")
    if "gravity_torques" not in harness.received:
        for topic in topics:
            harness.listen(JointState, topic)
        harness.joint_states = harness.publisher(JointState, "joint_states")
    inboxes = [harness.received[topic] for topic in topics]
    counts = [len(inbox) for inbox in inboxes]
    msg = JointState(name=list(names), position=[float(x) for x in q], velocity=[float(x) for x in qd])
    harness.joint_states.publish(msg)
    assert harness.spin_until(lambda: all(len(i) > c for i, c in zip(inboxes, counts))), "no torques"
    return inboxes[0][-1], inboxes[1][-1]


def pinocchio_gravity(model, q, link=None):
    """Pinocchio's gravity torques of Baxter, PAYLOAD appended at ``link`` (None: none)."""
    full, follows = pinocchio_of(BAXTER, mimic=True)
    if link is not None:
        frame = full.frames[full.getFrameId(link)]
        full.appendBodyToJoint(frame.parentJoint, spatial_inertia(PAYLOAD), frame.placement)
    return reference(full, follows, model, q, np.zeros(model.n), np.zeros(model.n))[1]


def test_id_node_on_a_whole_tree_gives_every_independent_joint_as_pinocchio():
    with running(IdNode, parameter_overrides=from_description()) as harness:
        model = harness.node.settings.model
        assert model.n == 17 and len(model.joints) == 19 and not model.is_chain
        rng = np.random.default_rng(7)
        q, qd = rng.uniform(-1.0, 1.0, model.n), rng.uniform(-1.0, 1.0, model.n)
        every = [j.name for j in model.joints]
        q_all, qd_all = model.all_positions(q), model.mimic_matrix() @ qd
        shuffled = rng.permutation(len(every))  # every joint, mimic ones too, in any order
        g_msg, tau_msg = answers(harness, [every[i] for i in shuffled], q_all[shuffled], qd_all[shuffled])
        tau, g, _ = reference(*pinocchio_of(BAXTER, mimic=True), model, q, qd, np.zeros(model.n))
        friction = 0.0 if model.friction is None else model.friction.torques(qd)
    assert tuple(g_msg.name) == tuple(tau_msg.name) == model.joint_names
    np.testing.assert_allclose(g_msg.effort, g, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(tau_msg.effort, tau + friction, rtol=1e-9, atol=1e-9)
    assert np.abs(g).max() > 1.0  # the arms' weight is in it


def test_a_payload_on_a_named_link_of_the_tree_as_pinocchio_and_none_without_a_link(monkeypatch):
    """(The kernels' Python form: the same numbers as the native one, which the whole tree's
    test above runs; each payload link is code of its own, compiled by gcc for seconds.)"""
    monkeypatch.setenv("IRB140_NATIVE", "0")
    values = dict(payload__link="left_gripper", payload__mass=PAYLOAD.mass, payload__com=list(PAYLOAD.com))
    values["payload__inertia"] = list(PAYLOAD.inertia)
    with running(IdNode, parameter_overrides=from_description(**values)) as harness:
        model = harness.node.settings.model
        q = np.random.default_rng(3).uniform(-1.0, 1.0, model.n)
        left, _ = answers(harness, model.joint_names, q, np.zeros(model.n))
        [refused] = harness.set_parameters([Parameter("payload.link", value="")])
        [unknown] = harness.set_parameters([Parameter("payload.link", value="no_such_link")])
        [moved] = harness.set_parameters([Parameter("payload.link", value="right_gripper")])
        harness.settle()
        right, _ = answers(harness, model.joint_names, q, np.zeros(model.n))
    np.testing.assert_allclose(left.effort, pinocchio_gravity(model, q, "left_gripper"), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(right.effort, pinocchio_gravity(model, q, "right_gripper"), rtol=1e-9, atol=1e-9)
    assert np.abs(np.subtract(left.effort, right.effort)).max() > 1.0  # the payload loads one arm, then the other
    assert not refused.successful and "payload.link" in refused.reason and "tree" in refused.reason
    assert not unknown.successful and "payload.link" in unknown.reason and "no_such_link" in unknown.reason
    assert moved.successful


def test_a_tree_payload_without_its_link_stops_a_tool_or_node_in_one_line():
    with pytest.raises(ValueError, match=r"^[^\n]*payload\.link: the model is a tree \(17 joints"):
        read_arm({"model.source": "robot_description", "robot_description": BAXTER, "payload.mass": 1.0})
    with pytest.raises(ValueError, match="payload.link names a URDF link"):
        read_arm({"payload.link": "tool0"})


def test_a_node_holds_the_rest_of_the_tree_where_model_held_positions_says():
    """id_node given a tip link and model.held_positions builds the model every tool reads
    from the same values (the other arm turned, its mimic fingers following), not the one at
    zero; a joint the URDF lacks stops its start in one line naming the parameter."""
    values = {"model.tip_link": "la2", "model.held_positions": ["r1=0.4", "r2=-0.7"]}
    described = [Parameter("model.source", value="robot_description"), Parameter("robot_description", value=TWO_ARMS)]
    with running(IdNode, parameter_overrides=described + [Parameter(k, value=v) for k, v in values.items()]) as harness:
        model = harness.node.settings.model
    q, qd, qdd = ([0.3, -0.2, 0.5], [0.1, 0.4, -0.3], [1.0, -0.5, 0.2])
    tool, zero = (read_arm(v, urdf=UrdfText(TWO_ARMS, "t")).model for v in (values, {"model.tip_link": "la2"}))
    np.testing.assert_array_equal(rnea(model, q, qd, qdd), rnea(tool, q, qd, qdd))
    assert abs(rnea(model, q, qd, qdd)[0] - rnea(zero, q, qd, qdd)[0]) > 0.01
    misspelt = [Parameter("model.held_positions", value=["r_1=0.4"])]
    with pytest.raises(ValueError) as refused, running(IdNode, parameter_overrides=described + misspelt):
        pass
    assert "model.held_positions r_1=0.4: the URDF has no joint 'r_1'; did you mean r1?" in str(refused.value)
    assert "\n" not in str(refused.value)


def test_markers_show_every_independent_joint_of_the_tree_at_pinocchios_joint_origins():
    model = load_urdf(BAXTER).model
    q = np.random.default_rng(5).uniform(-1.0, 1.0, model.n)
    tau = gravity(model, q)
    markers = build_markers(model, [np.inf] * model.n, "base", Time(), q, tau, external=tau * 0.1)
    spheres = {m.id: m for m in markers.markers if m.ns == "joint_load"}
    labels = [m.text for m in markers.markers if m.ns == "joint_label"]
    assert sorted(spheres) == list(range(model.n))
    assert [label.split(" ")[0] for label in labels] == list(model.joint_names)
    full, _ = pinocchio_of(BAXTER, mimic=False)
    data = full.createData()
    pin.forwardKinematics(
        full, data, pinocchio_state(full, [j.name for j in model.joints], model.all_positions(q), q, q)[0]
    )
    for k, name in enumerate(model.joint_names):
        p = spheres[k].pose.position
        joint = full.getJointId(name)  # its origin: the parent's frame placed, before the joint's own motion
        origin = (data.oMi[full.parents[joint]] * full.jointPlacements[joint]).translation
        np.testing.assert_allclose([p.x, p.y, p.z], origin, atol=1e-12)
    assert not [m for m in markers.markers if m.ns == "external_force" and m.action == m.ADD]  # no flange force


def test_external_torques_on_a_tree_and_no_wrench_said_in_one_line():
    with running(IdNode, parameter_overrides=from_description()) as harness:
        model = harness.node.settings.model
        q = np.random.default_rng(9).uniform(-1.0, 1.0, model.n)
        harness.listen(JointState, "external_torques")
        publisher = harness.publisher(JointState, "joint_states")
        g = gravity(model, q)
        for k in range(3):  # at rest, efforts = gravity: no external torque
            msg = JointState(name=list(model.joint_names), position=q.tolist(), velocity=[0.0] * model.n)
            msg.effort = g.tolist()
            msg.header.stamp.nanosec = 1000 * (k + 1)
            publisher.publish(msg)
        inbox = harness.received["external_torques"]
        assert harness.spin_until(lambda: len(inbox) >= 3), "no external torques"
        report = harness.node.wrench.report()
    assert tuple(inbox[-1].name) == model.joint_names
    np.testing.assert_allclose(inbox[-1].effort, 0.0, atol=1e-9)
    assert report == (False, TREE_REFUSAL, {}) and "\n" not in TREE_REFUSAL
    stream = WrenchStream()
    stream.note(model, q, g)
    with pytest.raises(ValueError, match="no external wrench on a tree"):
        stream.estimate("tip")


def within_limits(model, share):
    """A pose at ``share`` (0..1) of each independent joint's range."""
    lower, upper = np.array([joint.position_limits for joint in model.independent_joints]).T
    return (lower + share * (upper - lower)).tolist()


@pytest.mark.parametrize("arm", ["two_arms", "baxter"])
def test_sim_node_simulates_a_tree_held_by_its_gravity_torques(arm):
    """A torso and two arms (test_urdf_trees' TWO_ARMS, its mimic joints taken out), and
    Baxter (its mimic fingers held to their joints by MuJoCo equalities): every independent
    joint published, and the tree held where it is by the core's gravity torques (MuJoCo's
    bodies nested along model.parent); without them it falls."""
    text = _without_mimics(TWO_ARMS) if arm == "two_arms" else BAXTER
    model = load_urdf(text).model
    pose = within_limits(model, np.random.default_rng(6).uniform(0.2, 0.8, model.n))
    assert not model.is_chain and (model.mimics is None) == (arm == "two_arms")
    overrides = [Parameter("model.source", value="robot_description"), Parameter("robot_description", value=text)]
    overrides += [Parameter("initial_positions", value=pose), Parameter("command_timeout", value=0.0)]
    with running(SimNode, parameter_overrides=overrides) as sim:
        sim.states = sim.listen(JointState, "joint_states", 1000)
        sim.commands = sim.publisher(Float64MultiArray, "effort_commands")
        held = states_after_reset(sim, 300, gravity(model, pose))
        engine = sim.node.simulation.arm
        every_joint = engine.data.qpos.copy()  # MuJoCo's: the mimic joints too
        fall = states_after_reset(sim, 300, np.zeros(model.n))
    assert list(held[0].name) == list(model.joint_names)
    assert np.abs(np.array([msg.position for msg in held]) - pose).max() < 1e-6
    assert np.abs(every_joint - model.all_positions(pose)).max() < 1e-6  # each mimic joint where it follows
    assert np.abs(np.array(fall[-1].position) - pose).max() > 1e-2  # without them it falls


def pinocchio_link_torques(model, q, forces: dict) -> np.ndarray:
    """tau_ext = sum_k J_k^T F_k of wrenches (force; torque about the link's origin, in its
    axes) on Baxter's links, J_k Pinocchio's LOCAL frame Jacobian, projected on the
    independent joints."""
    full, follows = pinocchio_of(BAXTER, mimic=True)
    names = model.joint_names if follows else [j.name for j in model.joints]
    state = (q if follows else model.all_positions(q)), np.zeros(len(names)), np.zeros(len(names))
    pq = pinocchio_state(full, names, *state)[0]
    data = full.createData()
    index = [full.joints[full.getJointId(name)].idx_v for name in names]
    tau = np.zeros(full.nv)
    for link, F in forces.items():
        J = pin.computeFrameJacobian(full, data, pq, full.getFrameId(link), pin.ReferenceFrame.LOCAL)
        tau += J.T @ F
    return tau[index] if follows else model.mimic_matrix().T @ tau[index]


FORCES = {
    "left_gripper": np.array([5.0, -3.0, 8.0, 0.4, -0.2, 0.3]),
    "right_gripper": np.array([-2.0, 6.0, 1.0, 0.0, 0.5, -0.1]),
}


def test_link_wrenches_on_two_arms_are_the_wrenches_that_made_the_torques():
    loaded = load_urdf(BAXTER)
    model = loaded.model
    places = wrench_places(list(FORCES), loaded.carried)
    exact = 0
    for q in np.random.default_rng(12).uniform(-1.0, 1.0, (6, model.n)):
        tau_ext = pinocchio_link_torques(model, q, FORCES)
        wrenches, sigma, damping = link_wrenches(model, q, tau_ext, places)
        assert (damping == 0.0) == (sigma >= SINGULAR_THRESHOLD)
        if damping:  # near a singularity: damped, not exact
            continue
        exact += 1
        for wrench in wrenches:
            np.testing.assert_allclose(np.concatenate([wrench.force, wrench.torque]), FORCES[wrench.link], atol=1e-9)
    assert exact >= 3
    with pytest.raises(ValueError, match=r"^external_wrench\.links: 'base' is not moved by the model's joints$"):
        wrench_places(["base"], loaded.carried)
    with pytest.raises(
        ValueError, match=r"^external_wrench\.links: 'left_gripper' is named twice; name each link once$"
    ):
        wrench_places(["left_gripper", "right_gripper", "left_gripper"], loaded.carried)


def test_id_node_publishes_each_links_wrench_in_its_frame():
    overrides = from_description() + [Parameter("external_wrench.links", value=list(FORCES))]
    with running(IdNode, parameter_overrides=overrides) as harness:
        model = harness.node.settings.model
        q = np.random.default_rng(13).uniform(-1.0, 1.0, model.n)
        harness.listen(JointState, "external_torques")
        harness.listen(WrenchStamped, "external_wrench")
        publisher = harness.publisher(JointState, "joint_states")
        effort = gravity(model, q) + pinocchio_link_torques(model, q, FORCES)
        for k in range(5):
            msg = JointState(name=list(model.joint_names), position=q.tolist(), velocity=[0.0] * model.n)
            msg.effort, msg.header.stamp.nanosec = effort.tolist(), 1_000_000 * (k + 1)
            publisher.publish(msg)
        torques, wrenches = harness.received["external_torques"], harness.received["external_wrench"]
        assert harness.spin_until(lambda: len(torques) >= 5 and len(wrenches) >= 10), "no wrenches"
        report = harness.node.wrench.report()
    r = np.array(torques[-1].effort)  # the observer's, a lag of its gain: some of tau_ext by now
    expected, _, _ = link_wrenches(model, q, r, wrench_places(list(FORCES), load_urdf(BAXTER).carried))
    last = {msg.header.frame_id: msg.wrench for msg in wrenches[-2:]}
    assert sorted(last) == sorted(FORCES)
    for wrench in expected:
        w = last[wrench.link]
        np.testing.assert_allclose([w.force.x, w.force.y, w.force.z], wrench.force, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose([w.torque.x, w.torque.y, w.torque.z], wrench.torque, rtol=1e-9, atol=1e-9)
    assert np.abs(r).max() > 0.1 and not report[0]


def test_external_wrench_links_that_the_model_does_not_move_stop_the_start_in_one_line():
    overrides = from_description() + [Parameter("external_wrench.links", value=["left_gripper", "nowhere"])]
    with (
        pytest.raises(ValueError, match=r"^[^\n]*external_wrench\.links: 'nowhere' is not moved"),
        running(IdNode, parameter_overrides=overrides),
    ):
        pass


def test_payload_check_node_checks_the_payload_on_its_link_with_the_other_arm_in_its_worst_pose():
    """test_payload_tree's PITCH_TORSO: the torso's limit between the payload's worst torque
    with the other arm at zero and in its worst pose: OVER-LIMIT, at the tree's worst torque;
    its torque now the tree's gravity at the joint state (the other arm's pose in it); the
    report names the other arm's worst pose for the torso (its numbers: test_payload_tree)."""
    from std_srvs.srv import Trigger

    from irb140_dynamics.core.payload import workspace_load
    from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode

    from ..core.test_payload_tree import PAYLOAD as LOAD
    from ..core.test_payload_tree import PITCH_TORSO, tree

    worst = abs(workspace_load(tree(), LOAD, [np.inf] * 3).torque[0])
    values = dict(
        payload__link="la2", payload__mass=LOAD.mass, payload__com=list(LOAD.com), torso__torque_limit=worst - 1
    )
    overrides = from_description(diagnostics__period=0.0, **values)
    overrides[1] = Parameter("robot_description", value=PITCH_TORSO)
    with running(PayloadCheckNode, parameter_overrides=overrides) as harness:
        client = harness.probe.create_client(Trigger, "/payload_check_node/check")
        assert client.wait_for_service(timeout_sec=10)
        q = [0.3, -0.4, 0.7, 1.2, -0.9]
        harness.publisher(JointState, "joint_states").publish(
            JointState(name=["r2", "r1", "l2", "l1", "torso"], position=q[::-1])
        )
        assert harness.spin_until(lambda: harness.node.state is not None)
        reply = harness.call(lambda: client.call_async(Trigger.Request()))
        model = harness.node.model
    assert not reply.success and reply.message.startswith(
        f"OVER-LIMIT: 1.500 kg does not fit: torso needs {worst:.3f} N m at ("
    )
    now = gravity(model.with_payload(LOAD), q)[:3]
    rows = {line.split()[0]: float(line.split()[1]) for line in reply.message.splitlines()[3:6]}
    np.testing.assert_allclose([rows[name] for name in ("torso", "l1", "l2")], now, atol=5e-4)
    rest = reply.message.splitlines()[6]  # the other arm in the torso's worst pose: the one line of the rest
    assert rest.startswith("the rest of the tree in torso's worst pose [deg]: r1 ") and ", r2 " in rest
    assert "rest of the tree" not in "\n".join(reply.message.splitlines()[7:])


@pytest.mark.parametrize("node", [IdNode, PayloadCheckNode, SimNode])
def test_held_positions_on_an_arm_of_parameters_stop_a_node_in_one_line_as_a_tool(node):
    """model.held_positions holds joints of a URDF: on the built-in arm (no URDF) every node
    refuses it at its start in read_arm's line, as the tools do (it was warned about, ignored)."""
    with pytest.raises(ValueError) as tool:
        read_arm({"model.held_positions": ["joint_2=0.1"]})
    held = [Parameter("model.held_positions", value=["joint_2=0.1"])]
    with pytest.raises(ValueError) as refused, running(node, parameter_overrides=held):
        pass
    assert str(refused.value) == str(tool.value) and "\n" not in str(refused.value)
    assert str(tool.value).startswith("model.held_positions holds joints of a URDF")
