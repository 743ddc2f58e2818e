"""excitation and identify on arms with mimic joints, and excitation within torque limits.

identify: `excitation --urdf` of a chain with mimic joints (test_regressor_mimic's: one
before its joint in the file, a gripper's finger of multiplier -1, a prismatic one) moves
its independent joints within the limits of the mimic joints too; a recording of the true
arm (other masses, friction and armature on every joint, mimic joints included) is made of
rnea's torques with noise, its columns shuffled and the mimic joints' columns in it; the
arm `identify --urdf` fits predicts the true arm's torques on another motion, and its URDF
keeps the mimic joints.

excitation within torque limits: a torque limit below what the full motion needs scales the
motion down (the joints sharing that torque), the file's torques within the limit; one
below what any pose within the ranges needs at rest is refused in one line naming the
joint, the torque needed and the limit, nothing written."""

from dataclasses import replace

import numpy as np

from irb140_dynamics.core import Friction, RigidBody, rnea_batch
from irb140_dynamics.core.io.params_file import read_parameter_file
from irb140_dynamics.core.io.trajectory_file import read_joint_trajectory
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.trajectories.message import Trajectory
from irb140_dynamics.identification.excitation import Limits
from irb140_dynamics.identification.torque_limits import torque_sharers
from irb140_dynamics.tools import excitation, identify

from ..core.test_regressor_mimic import MIMIC_CHAIN
from ..core.test_urdf_trees import TWO_ARMS
from ..support.simulated_ur5 import write_csv
from .test_tree_identify_retime import errors_on_another_motion, gravity_batch, run

RATE = 200.0  # Hz: the recording


def true_arm(model: RobotModel) -> RobotModel:
    """``model`` with each link's mass and inertia scaled within [0.7, 1.3], viscous friction
    and armature on every joint, Coulomb friction where the model takes it."""
    factors = np.random.default_rng(5).uniform(0.7, 1.3, len(model.joints))
    joints = tuple(
        replace(
            j,
            link=RigidBody(j.link.mass * f, j.link.com, tuple(f * x for x in j.link.inertia)),
            friction=Friction(0.3, 0.2 if mimic is None or abs(mimic.multiplier) == 1.0 else 0.0),
            armature=0.02,
        )
        for j, f, mimic in zip(model.joints, factors, model.mimics)
    )
    return replace(model, joints=joints)


def points(path, model: RobotModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(t, Q, QD, QDD) of an excitation file's points, in the model's joint order."""
    tr = Trajectory.from_message(read_joint_trajectory(path), model.joint_names)
    return tr.t, tr.q, tr.qd, tr.qdd


def test_identify_fits_an_arm_with_mimic_joints_from_its_excitation(tmp_path, capsys):
    urdf = tmp_path / "mimic_chain.urdf"
    urdf.write_text(MIMIC_CHAIN)
    prior = load_urdf(MIMIC_CHAIN).model
    assert prior.joint_names == ("j1", "j2", "j3") and len(prior.joints) == 6
    excitation_file = tmp_path / "excitation.yaml"
    status, printed, err = run(
        capsys,
        excitation,
        "--urdf",
        urdf,
        "--out",
        excitation_file,
        "--iterations",
        0,
        "--period",
        4,
        "--harmonics",
        3,
        "--rate",
        RATE,
        "--periods",
        3,
    )
    assert status == 0, err
    t, Q, QD, QDD = points(excitation_file, prior)
    assert Q.shape[1] == 3  # the independent joints only
    positions = Q @ prior.mimic_matrix().T + [o for _, _, o in prior.coordinates]  # every joint's, mimic ones too
    for i, joint in enumerate(prior.joints):
        low, high = joint.position_limits
        assert low - 1e-9 <= positions[:, i].min() and positions[:, i].max() <= high + 1e-9, joint.name
    true = true_arm(prior)
    tau = rnea_batch(true, Q, QD, QDD)
    tau += np.random.default_rng(3).normal(0.0, 0.01 * np.abs(tau).max(axis=0), tau.shape)
    mimic = [i for i, m in enumerate(prior.mimics) if m is not None]
    names = [*prior.joint_names, *(prior.joints[i].name for i in mimic)]  # the mimic joints recorded too
    all_Q = np.hstack([Q, positions[:, mimic]])
    all_QD = np.hstack([QD, QD @ prior.mimic_matrix()[mimic].T])
    order = np.random.default_rng(2).permutation(len(names))
    recording = write_csv(
        tmp_path / "recording.csv",
        [names[i] for i in order],
        t,
        all_Q[:, order],
        all_QD[:, order],
        np.hstack([tau, np.zeros((len(t), len(mimic)))])[:, order],
    )
    out = tmp_path / "identified.yaml"
    status, printed, err = run(capsys, identify, recording, "--urdf", urdf, "--out", out, "--quiet")
    assert status == 0, err
    identified = RobotModel.from_params(read_parameter_file(out))
    assert identified.joint_names == prior.joint_names and identified.mimics == prior.mimics
    error, before, Qo = errors_on_another_motion(true, prior, identified)
    assert np.all(error <= 0.05), error
    assert np.sqrt(np.mean(error**2)) * 3 <= np.sqrt(np.mean(before**2))
    back = load_urdf((tmp_path / "identified.urdf").read_text()).model  # the identified arm as URDF:
    assert back.mimics == prior.mimics  # its mimic joints, and the inertials of every link
    np.testing.assert_allclose(gravity_batch(back, Qo), gravity_batch(identified, Qo), rtol=1e-6, atol=1e-6)


def test_excitation_scales_its_motion_down_within_a_torque_limit(tmp_path, capsys):
    urdf = tmp_path / "mimic_chain.urdf"
    urdf.write_text(MIMIC_CHAIN)
    out = tmp_path / "excitation.yaml"
    args = ["--urdf", urdf, "--out", out, "--iterations", 0, "--period", 2, "--harmonics", 2, "--rate", 200]
    status, printed, err = run(capsys, excitation, *args, "-p", "j3.torque_limit:=4.5")
    assert status == 0, err
    model = load_urdf(MIMIC_CHAIN).model
    line = next(line for line in printed.splitlines() if line.startswith("scaled down for the torque limits"))
    needed = float(line.split("needed j3 ")[1].split(" N m")[0])
    assert needed > 4.5 and "(limit 4.5)" in line  # the full motion needs more than the limit
    _, Q, QD, QDD = points(out, model)
    peak = np.abs(rnea_batch(model, Q, QD, QDD)).max(axis=0)
    assert 0.9 * 4.5 < peak[2] <= 4.5, peak  # scaled to the limit, not far below it
    positions = Q @ model.mimic_matrix().T + [o for _, _, o in model.coordinates]  # toward the holding pose:
    for i, joint in enumerate(model.joints):  # still within every joint's range, mimic joints' too
        assert joint.position_limits[0] <= positions[:, i].min() <= positions[:, i].max() <= joint.position_limits[1]
    assert line in out.read_text()  # the file's header says so too


def test_excitation_refuses_a_torque_limit_the_arm_cannot_hold(tmp_path, capsys):
    """Every joint kept within 0.05 rad of a bent pose: j3's torque at rest in the poses the
    ranges allow is within those of the box's corners; a limit of half the least of them
    cannot be kept."""
    urdf = tmp_path / "mimic_chain.urdf"
    urdf.write_text(MIMIC_CHAIN)
    narrow = [f"-p j{j}.position_limits:=[{low},{low + 0.05}]" for j, low in ((1, 0.0), (2, 0.5), (3, 0.8))]
    model = load_urdf(MIMIC_CHAIN).model
    corners = np.array([[q1, q2, q3] for q1 in (0.0, 0.05) for q2 in (0.5, 0.55) for q3 in (0.8, 0.85)])
    at_rest = np.abs(rnea_batch(model, corners, 0 * corners, 0 * corners)[:, 2])
    limit = round(float(at_rest.min()) / 2, 3)
    out = tmp_path / "out.yaml"
    status, _, err = run(
        capsys, excitation, "--urdf", urdf, "--out", out, *" ".join(narrow).split(), "-p", f"j3.torque_limit:={limit}"
    )
    lines = err.strip().splitlines()
    assert status == 1 and len(lines) == 1, err
    needed = float(lines[0].split("it needs ")[1].split(" N m")[0])
    assert 0.99 * at_rest.min() <= needed <= 1.01 * at_rest.max()
    assert lines[0].startswith("excitation: error: j3: at rest within the position ranges")
    assert f"its torque limit {limit:g} N m" in lines[0]
    assert [p.name for p in tmp_path.iterdir()] == ["mimic_chain.urdf"]


def test_the_joints_sharing_a_torque_are_its_branch():
    """On a tree, the coordinates whose motion enters l2's torque are those above and below
    it (torso, l1, l2), not the other arm's; r2's include its mimic fingers' joint (r1 carries
    finger_b) and the torso."""
    model = load_urdf(TWO_ARMS).model
    names = model.joint_names
    assert [names[k] for k in torque_sharers(model, names.index("l2"))] == ["torso", "l1", "l2"]
    assert [names[k] for k in torque_sharers(model, names.index("r2"))] == ["torso", "r1", "r2"]


def test_a_coordinates_limits_are_its_joints_and_its_mimic_joints():
    """j3's range is its own within the image of finger's (q = -q3 + 0.05 in [-2, 2]: q3 in
    [-1.95, 2.05]); its speed and acceleration those of parallel (multiplier -0.6) over 0.6
    when they bind; j2's speed its own (slide follows it with 0.5: 2 rad/s would bind less)."""
    model = load_urdf(MIMIC_CHAIN).model
    names = [j.name for j in model.joints]
    joints = list(model.joints)
    joints[names.index("parallel")] = replace(
        joints[names.index("parallel")], velocity_limit=0.3, acceleration_limit=1.2
    )
    limits = Limits.of(replace(model, joints=tuple(joints)), 0.0)
    np.testing.assert_allclose(limits.lower, [-2.0, -2.0, -1.95], rtol=0, atol=1e-15)
    np.testing.assert_allclose(limits.upper, [2.0, 2.0, 2.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(limits.speed, [1.0, 1.0, 0.5], rtol=1e-15)
    np.testing.assert_allclose(limits.acceleration, [5.0, 5.0, 2.0], rtol=1e-15)
