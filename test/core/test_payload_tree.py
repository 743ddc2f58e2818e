"""The payload check on a tree (core.payload.path): the joints up to the payload's link, with
the rest of the tree in its worst pose, against the tree's own gravity torques (the core's
gravity, itself Pinocchio's: test_urdf_trees) at dense samples of the other arm's poses.

PITCH_TORSO: a torso pitching about y (an axis across gravity), the payload's arm on one
side and, on the other, an arm whose heavy link swings its CoM over a whole sphere about
its shoulder: there the bound of the other arm's share is exact, |g| m_S r_S."""

from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics.core import RigidBody
from irb140_dynamics.core.dynamics import gravity_batch
from irb140_dynamics.core.io.arm_source import read_arm
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.payload import check_payload, derive_torque_limits, workspace_load
from irb140_dynamics.core.payload.path import payload_path

from ..support.urdf_support import arm_text
from .test_urdf_trees import TWO_ARMS

G = 9.81
PAYLOAD = RigidBody(1.5, (0.05, 0.0, 0.02))


def _link(name, mass, com="0 0 0"):
    inertia = '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>'
    return f'<link name="{name}"><inertial><origin xyz="{com}"/><mass value="{mass}"/>{inertia}</inertial></link>'


def _joint(name, parent, child, xyz, axis, lower, upper, effort=1000.0):
    return (
        f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}"/><axis xyz="{axis}"/>'
        f'<limit lower="{lower}" upper="{upper}" effort="{effort}" velocity="1"/></joint>'
    )


PITCH_TORSO = f"""<robot name="pitch_torso"><link name="base"/>
  {_joint("torso", "base", "torso", "0 0 0.3", "0 1 0", -0.6, 0.6)}{_link("torso", 5.0, "0 0 0.2")}
  {_joint("l1", "torso", "la1", "0 0.2 0.5", "0 1 0", -1.5, 1.5)}{_link("la1", 2.0, "0.15 0 0")}
  {_joint("l2", "la1", "la2", "0.3 0 0", "0 1 0", -2.0, 2.0)}{_link("la2", 1.0, "0.1 0 0")}
  {_joint("r1", "torso", "ra1", "0 -0.2 0.5", "0 0 1", -3.1416, 3.1416)}{_link("ra1", 1.0)}
  {_joint("r2", "ra1", "ra2", "0 0 0", "0 1 0", -1.5708, 1.5708)}{_link("ra2", 3.0, "0.3 0 0")}
</robot>"""
OTHER_ARM_SHARE = G * 3.0 * 0.3  # N m: |g| m_S r_S of the right arm, at the torso joint


def tree(text=PITCH_TORSO, link="la2"):
    return load_urdf(text).with_flange_at(link)


def with_limit(model, name, limit):
    return replace(model, joints=tuple(replace(j, torque_limit=limit) if j.name == name else j for j in model.joints))


def sampled_worst(model, payload, poses):
    """max |tau_j| of the path's joints over the tree's poses (N, n_tree), the payload on."""
    path = payload_path(model)
    return np.abs(gravity_batch(model.with_payload(payload), poses)[:, path.columns]).max(axis=0)


def dense_poses(model, count, rng):
    lower, upper = np.array([j.position_limits for j in model.independent_joints]).T
    return rng.uniform(lower, upper, (count, model.n))


def test_the_path_folds_each_side_branch_at_its_pivot_and_bounds_its_poses_exactly_here():
    model = tree()
    path = payload_path(model)
    assert path.chain.joint_names == ("torso", "l1", "l2") and path.moves
    np.testing.assert_allclose(path.slack, [OTHER_ARM_SHARE, 0.0, 0.0], rtol=1e-8)
    torso = path.chain.joints[0].link
    assert torso.mass == pytest.approx(5.0 + 4.0)  # the right arm's 4 kg at its shoulder
    np.testing.assert_allclose(torso.com, (5.0 * np.array([0, 0, 0.2]) + 4.0 * np.array([0, -0.2, 0.5])) / 9.0)


def test_the_worst_static_torques_bound_every_sampled_pose_and_meet_them_where_the_bound_is_exact():
    """Over 20000 poses of the whole tree, no torque of the path's joints beyond its bound;
    at the torso's worst pose of the path, the other arm's densest sampled pose (60 x 60 of
    its two joints) reaches the bound to the grid's resolution, and the torque found to 1e-9."""
    model = tree()
    limits = derive_torque_limits(model)
    load = workspace_load(model, PAYLOAD, limits)
    rng = np.random.default_rng(40)
    sampled = sampled_worst(model, PAYLOAD, dense_poses(model, 20000, rng))
    assert np.all(sampled <= load.bound * (1 + 1e-9) + 1e-12)
    assert np.all(np.abs(load.torque) <= load.bound)
    np.testing.assert_allclose(np.abs(load.torque), load.bound, rtol=1e-8)  # the bound is exact: found
    r1, r2 = np.meshgrid(np.linspace(-np.pi, np.pi, 60), np.linspace(-np.pi / 2, np.pi / 2, 60))
    poses = np.tile(np.r_[load.pose[0], 0.0, 0.0], (r1.size, 1))
    poses[:, 3], poses[:, 4] = r1.ravel(), r2.ravel()
    grid = sampled_worst(model, PAYLOAD, poses)[0]
    assert load.bound[0] - 0.01 * OTHER_ARM_SHARE <= grid <= load.bound[0] * (1 + 1e-9)
    at_zero = sampled_worst(model, PAYLOAD, np.r_[load.pose[0], 0.0, 0.0][None])[0]
    assert load.bound[0] - at_zero > 1.0  # the other arm's pose matters here


def test_a_payload_fitting_with_the_other_arm_at_zero_is_over_the_limit_in_its_worst_pose():
    """The chain to la2 holds the right arm at zero (load_urdf with tip_link): the payload
    fits there; on the tree the right arm's worst pose puts the torso over its limit."""
    at_zero = load_urdf(PITCH_TORSO, tip_link="la2").model
    whole = tree()
    zero_worst = abs(workspace_load(at_zero, PAYLOAD, [np.inf] * 3).torque[0])
    tree_worst = abs(workspace_load(whole, PAYLOAD, [np.inf] * 3).torque[0])
    assert tree_worst > zero_worst + 1.0
    limit = 0.5 * (zero_worst + tree_worst)
    fits = check_payload(with_limit(at_zero, "torso", limit), PAYLOAD, q=np.zeros(3))
    over = check_payload(with_limit(whole, "torso", limit), PAYLOAD, q=np.zeros(whole.n))
    assert fits.verdict == "OK" and over.verdict == "OVER-LIMIT" and over.over == ["torso"]
    assert over.headline().startswith(f"OVER-LIMIT: 1.500 kg does not fit: torso needs {tree_worst:.3f} N m at (")
    assert over.joint_names == ("torso", "l1", "l2") and len(over.q) == 3
    # the report says the whole tree's worst pose of each joint: the torque found is the tree's there
    pose = over.workspace.tree_pose[0]
    np.testing.assert_array_equal(pose[:3], over.workspace.pose[0])
    there = gravity_batch(whole.with_payload(PAYLOAD), pose[None])[0, 0]
    assert there == pytest.approx(over.workspace.torque[0], rel=1e-12)
    rest = ", ".join(f"{name} {round(np.degrees(x), 1) + 0.0:g}" for name, x in zip(("r1", "r2"), pose[3:]))
    assert f"the rest of the tree in torso's worst pose [deg]: {rest}" in over.report().splitlines()
    assert over.joint_figures(0)["rest of the tree in the worst pose [deg]"] == rest
    assert fits.workspace.rest_pose == () and "rest of the tree" not in fits.report()


def test_the_state_and_the_largest_payload_on_the_tree_are_the_trees_torques():
    """Now: the tree's gravity with the payload at its state (the other arm's pose in it);
    the largest payload over the workspace holds in every sampled pose of the tree."""
    model = with_limit(tree(), "torso", 60.0)
    q = np.array([0.3, -0.4, 0.7, 1.2, -0.9])
    result = check_payload(model, PAYLOAD, q=q)
    expected = gravity_batch(model.with_payload(PAYLOAD), q[None])[0, :3]
    np.testing.assert_allclose(result.torque, expected, rtol=1e-12, atol=1e-12)
    best = result.workspace.max_payload
    assert 0.0 < best.mass < np.inf and best.joint == 0
    heavier = RigidBody(best.mass, PAYLOAD.com)
    poses = dense_poses(model, 20000, np.random.default_rng(41))
    assert sampled_worst(model, heavier, poses)[0] <= 60.0 * (1 + 1e-9)


def test_a_bound_not_met_is_said_and_baxters_other_arm_adds_nothing():
    """TWO_ARMS' other arm cannot stretch along g x z of its torso: the gap is the rest of
    the tree's, said so; the torques found (its fingers mimic r2) above every sampled one. On a tree whose other branches hang off the base, the path is the
    chain itself: nothing added, the same proofs."""
    model = load_urdf(TWO_ARMS).with_flange_at("la2")
    result = check_payload(model, RigidBody(1.0, (0.05, 0.0, 0.0)))
    sampled = sampled_worst(
        model, RigidBody(1.0, (0.05, 0.0, 0.0)), dense_poses(model, 20000, np.random.default_rng(4))
    )
    assert np.all(sampled <= result.workspace.bound * (1 + 1e-9) + 1e-12)
    assert np.all(np.abs(result.workspace.torque) >= sampled)  # its mimic fingers' coordinate searched on a grid
    assert result.workspace.gap[0] > 0.05 and "the rest of the tree's worst pose is bounded" in result.gap_note(0)
    off_base = PITCH_TORSO.replace(
        '<parent link="torso"/><child link="ra1"/>', '<parent link="base"/><child link="ra1"/>'
    )
    path = payload_path(tree(off_base))
    assert not path.moves and not path.slack.any()
    alone = workspace_load(load_urdf(off_base, tip_link="la2").model, PAYLOAD, [np.inf] * 3)
    on_tree = workspace_load(tree(off_base), PAYLOAD, [np.inf] * 3)
    np.testing.assert_array_equal(on_tree.torque, alone.torque)
    np.testing.assert_array_equal(on_tree.bound, alone.bound)


def test_a_payload_inside_a_chain_carries_the_joints_after_it_as_a_branch():
    """UR5 with payload.link wrist_2_link: the joints up to it, wrist_3 a branch (its CoM on
    its pivot: nothing added), no sampled pose of the whole arm above the bounds."""
    values = {"model.source": "robot_description", "robot_description": arm_text("ur5"), "model.tip_link": "tool0"}
    model = read_arm(values | {"payload.link": "wrist_2_link"}).model
    result = check_payload(model, PAYLOAD, q=np.zeros(model.n))
    assert result.joint_names == model.joint_names[:5] and result.verdict == "OK"
    sampled = sampled_worst(model, PAYLOAD, dense_poses(model, 20000, np.random.default_rng(5)))
    assert np.all(sampled <= result.workspace.bound * (1 + 1e-9) + 1e-12)


def test_a_mimic_joint_on_the_path_is_refused_in_one_line():
    model = load_urdf(TWO_ARMS).with_flange_at("fa")
    with pytest.raises(ValueError, match=r"^[^\n]*without mimic joints: 'finger_a' is one"):
        check_payload(model, RigidBody(1.0))


def test_branches_of_mimic_joints_following_the_path_widen_its_bounds():
    """TWO_ARMS to ra2: its fingers follow r2, a joint of the path, and hang off it (no
    coordinate of their own): their poses still add to the path's torques, so the bounds
    take them (they were the folded chain's alone: r2's 2.44 N m under 4.13 sampled)."""
    model = load_urdf(TWO_ARMS, tip_link="ra2").model
    path = payload_path(model)
    assert path.moves and path.slack.all() and path.rest.size == 0
    result = check_payload(model, PAYLOAD)
    sampled = sampled_worst(model, PAYLOAD, dense_poses(model, 4000, np.random.default_rng(6)))
    assert np.all(sampled <= result.workspace.bound * (1 + 1e-9) + 1e-12)
    assert np.all(np.abs(result.workspace.torque) >= sampled)  # found on the tree: real torques
