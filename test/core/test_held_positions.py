"""The rest of a tree held at the positions given (core.io.urdf.held, read through
core.io.arm_source.read_arm as every node and tool reads an arm): a chain's torques are the
whole tree's at the same positions with the held joints at rest (test_urdf_trees' TWO_ARMS:
the other arm and its mimic fingers, a payload on a held link; test_payload_tree's pitching
torso above base_link, turning gravity); the load diagram's masses move where the held arm
loads a joint (the torso) and stay where it cannot (the last joint). The tools' --hold:
test/tools/test_hold_option.py."""

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from irb140_dynamics.core import RigidBody, gravity, mass_matrix, rnea
from irb140_dynamics.core.io.arm_source import HeldPositionError, UrdfText, model_summary, read_arm
from irb140_dynamics.core.io.urdf import UrdfError, load_urdf
from irb140_dynamics.core.payload import derive_torque_limits
from irb140_dynamics.core.payload.diagram import load_diagram

from ..support.pinocchio_trees import corpus_files, pinocchio_state, worst_error
from .test_payload_tree import PITCH_TORSO, _joint, _link
from .test_urdf_trees import TWO_ARMS
from .test_urdf_trees import _joint as _tree_joint
from .test_urdf_trees import _link as _tree_link

PAYLOAD = RigidBody(1.5, (0.05, -0.02, 0.03))
# PITCH_TORSO with torque limits: the torso limits a payload near the flange, l2 one far off it
LIMITED = f"""<robot name="limited_torso"><link name="base"/>
  {_joint("torso", "base", "torso", "0 0 0.3", "0 1 0", -0.6, 0.6, effort=120)}{_link("torso", 5.0, "0 0 0.2")}
  {_joint("l1", "torso", "la1", "0 0.2 0.5", "0 1 0", -1.5, 1.5, effort=200)}{_link("la1", 2.0, "0.15 0 0")}
  {_joint("l2", "la1", "la2", "0.3 0 0", "0 1 0", -2.0, 2.0, effort=15)}{_link("la2", 1.0, "0.1 0 0")}
  {_joint("r1", "torso", "ra1", "0 -0.2 0.5", "0 0 1", -3.1416, 3.1416)}{_link("ra1", 1.0)}
  {_joint("r2", "ra1", "ra2", "0 0 0", "0 1 0", -1.5708, 1.5708)}{_link("ra2", 3.0, "0.3 0 0")}
</robot>"""


def arm(text, tip="la2", base=None, hold=(), **values):
    return read_arm({name.replace("__", "."): v for name, v in values.items()}, None, UrdfText(text, "t"), base, tip,
                    hold=hold)  # fmt: skip


def whole_tree_at(whole, chain, q, held):
    """The whole tree's joint vector: the chain's values by name, the held positions, the rest 0."""
    named = {**dict(zip(chain.joint_names, q)), **held}
    return np.array([named.get(name, 0.0) for name in whole.joint_names])


def test_the_chain_with_the_other_arm_held_is_the_whole_tree_at_those_positions():
    held = {"r1": 0.4, "r2": -0.7}  # the params file's r2 = 0.1 under --hold's
    chain = arm(TWO_ARMS, hold=["r2=-0.7"], model__held_positions=["r1=0.4", "r2=0.1"])
    # finger_b follows r2 as -0.5 r2 + 0.01 (prismatic, m), finger_a as 2 r2 + 0.2
    assert chain.urdf.held_summary() == "held: r1=0.4, r2=-0.7, finger_b=0.36, finger_a=-1.2"
    assert model_summary(chain.urdf) == "base -> la2, 3 joints ['torso', 'l1', 'l2']; " + chain.urdf.held_summary()
    assert model_summary(load_urdf(TWO_ARMS)) == "the tree below base, 5 joints ['torso', 'l1', 'l2', 'r1', 'r2']"
    whole = load_urdf(TWO_ARMS).model
    on_chain = [whole.joint_names.index(name) for name in chain.model.joint_names]
    rng = np.random.default_rng(40)
    for _ in range(3):
        q, qd, qdd = (rng.uniform(-1.0, 1.0, chain.model.n) for _ in range(3))
        expected = rnea(whole, whole_tree_at(whole, chain.model, q, held), *(
            whole_tree_at(whole, chain.model, v, {}) for v in (qd, qdd)))  # fmt: skip
        np.testing.assert_allclose(rnea(chain.model, q, qd, qdd), expected[on_chain], rtol=1e-12, atol=1e-12)
    # a payload on a link of the held arm: carried by the torso through the held joints
    carrying = arm(TWO_ARMS, hold=["r1=0.4", "r2=-0.7"], payload__link="fa", payload__mass=PAYLOAD.mass,
                   payload__com=list(PAYLOAD.com))  # fmt: skip
    whole_carrying = read_arm({"payload.link": "fa", "payload.mass": PAYLOAD.mass, "payload.com": list(PAYLOAD.com)},
                              urdf=UrdfText(TWO_ARMS, "t")).model  # fmt: skip
    q = rng.uniform(-1.0, 1.0, chain.model.n)
    at = {**held, "finger_b": 0.36, "finger_a": -1.2}
    expected = gravity(whole_carrying, whole_tree_at(whole, chain.model, q, held))[on_chain]
    np.testing.assert_allclose(gravity(carrying.model, q), expected, rtol=1e-12, atol=1e-12)
    assert dict(carrying.urdf.held_positions) == pytest.approx(at, abs=1e-15)


def test_a_torso_above_base_link_held_turns_gravity():
    held = {"torso": 0.4, "r2": 0.9}
    chain = arm(PITCH_TORSO, base="torso", hold=[f"{name}={value}" for name, value in held.items()])
    assert chain.model.gravity == pytest.approx((9.81 * np.sin(0.4), 0.0, -9.81 * np.cos(0.4)), abs=1e-15)
    whole = load_urdf(PITCH_TORSO).model
    on_chain = [whole.joint_names.index(name) for name in chain.model.joint_names]
    q = np.array([0.3, -0.5])
    expected = gravity(whole, whole_tree_at(whole, chain.model, q, held))[on_chain]
    np.testing.assert_allclose(gravity(chain.model, q), expected, rtol=1e-12, atol=1e-12)


def test_the_load_diagram_moves_where_the_held_arm_loads_a_joint_and_only_there():
    """At l = 0 the torso limits the payload, and the other arm's pose changes its torque; at
    l = 0.2 m the last joint does, whose torque no pose of the other arm touches."""
    masses = []
    for hold in ((), ("r2=1.2",)):
        model = arm(LIMITED, hold=hold).model
        diagram = load_diagram(model, derive_torque_limits(model).values, np.array([0.0]), np.array([0.0, 0.2]))
        assert [p.joint for p in diagram.points] == [0, 2] and all(p.proven for p in diagram.points)
        masses.append([p.mass for p in diagram.points])
    (torso_zero, last_zero), (torso_held, last_held) = masses
    assert torso_held > 1.05 * torso_zero  # r2 at 1.2 rad swings the other arm's CoM nearer the torso's axis
    assert last_held == pytest.approx(last_zero, rel=1e-9)


def whole_tree_error(chain, whole, rng, held=None):
    """The largest difference of the chain's rnea, gravity and M from the whole tree's (its
    mimic joints following the state; ``held``: the rest's positions, else 0) at random states."""
    on_chain = [whole.joint_names.index(name) for name in chain.joint_names]
    worst = 0.0
    for _ in range(3):
        q, qd, qdd = (rng.uniform(-1.0, 1.0, chain.n) for _ in range(3))
        at = whole_tree_at(whole, chain, q, held or {})
        rates = [whole_tree_at(whole, chain, v, {}) for v in (qd, qdd)]
        for ours, theirs in (
            (rnea(chain, q, qd, qdd), rnea(whole, at, *rates)[on_chain]),
            (gravity(chain, q), gravity(whole, at)[on_chain]),
            (mass_matrix(chain, q), mass_matrix(whole, at)[np.ix_(on_chain, on_chain)]),
        ):
            worst = max(worst, float(np.max(np.abs(ours - theirs))))
    return worst


def test_mimic_joints_off_the_chain_follow_the_chains_joint_as_in_the_whole_tree():
    """TWO_ARMS to ra2: finger_b (on ra1) and finger_a (on ra2) follow r2, a joint of the chain:
    they hang off it as mimic joints of the model (not held at zero), its torques the whole
    tree's; holding one is refused as a joint of the model, as holding r2 is."""
    chain = arm(TWO_ARMS, tip="ra2")
    model = chain.model
    assert model.joint_names == ("torso", "r1", "r2") and [j.name for j in model.joints][3:] == ["finger_b", "finger_a"]
    assert model.parent == (-1, 0, 1, 1, 2) and model.flange_joint == "r2"
    assert "finger_a" not in chain.urdf.held_joints and chain.urdf.held_joints == ("l1", "l2")
    whole = load_urdf(TWO_ARMS).model
    assert whole_tree_error(model, whole, np.random.default_rng(41)) < 1e-12
    for name in ("finger_a", "r2"):
        with pytest.raises(HeldPositionError, match=rf"^--hold {name}=0.1: a (mimic )?joint of the model"):
            arm(TWO_ARMS, tip="ra2", hold=[f"{name}=0.1"])


def test_the_pr2_gripper_follows_the_finger_the_chain_ends_at_as_pinocchio():
    """PR2 to its left finger tip, the finger at 0.5 rad: the other finger, its tip and the
    parallel links follow it as in Pinocchio's mimic=True model (they were held at zero:
    0.04 N m off)."""
    files = [path for path in corpus_files() if path.endswith("pr2_description/urdf/pr2.urdf")]
    if not files:
        pytest.skip("example-robot-data is not installed")
    text = Path(files[0]).read_text()
    loaded = load_urdf(text, tip_link="l_gripper_l_finger_tip_link")
    followers = {"l_gripper_r_finger_joint", "l_gripper_l_parallel_root_joint", "l_gripper_r_parallel_root_joint"}
    assert followers | {"l_gripper_r_finger_tip_joint"} <= {j.name for j in loaded.model.joints}
    assert not followers & set(loaded.held_joints)
    assert worst_error(text, loaded.model, np.random.default_rng(42), states=1, held=loaded.held_positions) < 1e-9
    full = pin.buildModelFromXML(text, mimic=True)
    q = np.zeros(loaded.model.n)
    q[-1] = 0.5  # l_gripper_l_finger_joint
    pq, _, _ = pinocchio_state(full, loaded.model.joint_names, q, q, q)
    index = [full.joints[full.getJointId(name)].idx_v for name in loaded.model.joint_names]
    expected = pin.computeGeneralizedGravity(full, full.createData(), pq)[index]
    np.testing.assert_allclose(gravity(loaded.model, q), expected, rtol=1e-9, atol=1e-9)


def test_a_mimic_joint_not_given_follows_its_joint_at_zero_as_when_given_zero():
    """TWO_ARMS to la2: r2 not given is at 0, and its fingers at their offsets (finger_b
    0.01 m, finger_a 0.2 rad), as with --hold r2=0 and as the whole tree with r2 at 0."""
    default, explicit = arm(TWO_ARMS), arm(TWO_ARMS, hold=["r2=0"])
    assert (
        dict(default.urdf.held_positions)
        == dict(explicit.urdf.held_positions)
        == {
            "finger_b": pytest.approx(0.01, abs=1e-15),
            "finger_a": pytest.approx(0.2, abs=1e-15),
        }
    )
    q = np.array([0.3, -0.4, 0.8])
    assert np.array_equal(gravity(default.model, q), gravity(explicit.model, q))
    assert whole_tree_error(default.model, load_urdf(TWO_ARMS).model, np.random.default_rng(43)) < 1e-12


# PITCH_TORSO with r2's range excluding zero: not given, it is held at its nearest limit
R2_BELOW_ZERO = PITCH_TORSO.replace('<child link="ra2"/><origin xyz="0 0 0"/><axis xyz="0 1 0"/>'
                                    '<limit lower="-1.5708" upper="1.5708"',
                                    '<child link="ra2"/><origin xyz="0 0 0"/><axis xyz="0 1 0"/>'
                                    '<limit lower="-1.5708" upper="-0.3"')  # fmt: skip


def test_a_joint_whose_range_excludes_zero_is_held_at_its_nearest_limit_and_said_so():
    assert R2_BELOW_ZERO != PITCH_TORSO
    default = arm(R2_BELOW_ZERO)
    assert dict(default.urdf.held_positions) == {"r2": -0.3}
    assert default.urdf.notes == (
        'joint "r2": not given, held at -0.3 rad, its limit nearest zero (zero is outside its range); '
        "give its position to hold it elsewhere",
    )
    explicit = arm(R2_BELOW_ZERO, hold=["r2=-0.3"])
    q = np.array([0.2, -0.5, 0.9])
    assert np.array_equal(gravity(default.model, q), gravity(explicit.model, q)) and explicit.urdf.notes == ()
    whole = load_urdf(R2_BELOW_ZERO).model
    assert whole_tree_error(default.model, whole, np.random.default_rng(44), {"r2": -0.3}) < 1e-12
    with pytest.raises(HeldPositionError, match=r"--hold r2=0: 0 rad is outside its limits \[-1.5708, -0.3\] rad"):
        arm(R2_BELOW_ZERO, hold=["r2=0"])


def test_a_mimic_of_a_mimic_off_the_chain_follows_the_chains_joint_and_one_above_base_link_is_refused():
    """Off the chain j1, j2: m1 follows j2 (2 q + 0.1), m2 follows m1 (-0.5 q + 0.3): both
    the model's, m2 following j2 as -q + 0.25. A mimic joint of j2 above base_link would turn
    base_link with the state: refused in one line."""
    links = "".join(_tree_link(name) for name in ("a", "b", "c", "d", "e"))
    text = f"""<robot name="mimics"><link name="root"/>{links}
      {_tree_joint("j1", "root", "a")}{_tree_joint("j2", "a", "b")}
      {_tree_joint("m1", "a", "c", extra='<mimic joint="j2" multiplier="2" offset="0.1"/>')}
      {_tree_joint("m2", "c", "d", extra='<mimic joint="m1" multiplier="-0.5" offset="0.3"/>')}
      {_tree_joint("up", "root", "e", extra='<mimic joint="j2"/>')}</robot>"""
    model = load_urdf(text, tip_link="b").model
    assert [j.name for j in model.joints] == ["j1", "j2", "m1", "m2"] and model.parent == (-1, 0, 0, 2)
    np.testing.assert_allclose(model.all_positions([0.3, 0.4]), [0.3, 0.4, 0.9, -0.15], rtol=1e-15)
    below_up = text.replace('<parent link="root"/><child link="a"/>', '<parent link="e"/><child link="a"/>')
    with pytest.raises(UrdfError, match=r'^URDF joint "up": a mimic joint above base_link \'e\' following \'j2\''):
        load_urdf(below_up, base_link="e", tip_link="b")


def test_names_of_a_urdf_on_an_arm_of_parameters_are_refused_in_a_nodes_words():
    """A node has no --urdf: read_arm (what nodes and tools share) names model.urdf_file; the
    tools' words are their own (test/tools/test_hold_option.py: give --urdf)."""
    for values in ({"model.held_positions": ["joint_2=0.1"]}, {"payload.link": "link_3"}):
        with pytest.raises(ValueError) as refused:
            read_arm(values)
        assert "model.source: robot_description with model.urdf_file" in str(refused.value)
        assert "--urdf" not in str(refused.value)
