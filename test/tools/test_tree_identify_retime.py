"""identify and retime on whole trees.

identify: `excitation --urdf` of a two-arm tree (test_urdf_trees' TWO_ARMS, its fingers
independent joints) is played by MuJoCo's true tree (other link masses, friction,
armature) under computed torque; the recording (columns in a shuffled order) is fitted
by `identify --urdf` with the file's inertials as the prior, and the identified tree
predicts the true tree's torques on another motion (mimic joints: test_mimic_identify).

retime: a JointTrajectory naming Baxter's joints in a shuffled order is checked: the peak
torques reported are the core's rnea (mimic fingers included) along the controller's
interpolation; a motion over a torque limit is reported as such, naming the joint."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from irb140_dynamics.core import Friction, RigidBody, gravity, mass_matrix, rnea_batch
from irb140_dynamics.core.io.params_file import read_parameter_file
from irb140_dynamics.core.io.trajectory_file import read_joint_trajectory
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.trajectories.check import check_trajectory
from irb140_dynamics.core.trajectories.interpolation import spline
from irb140_dynamics.core.trajectories.message import Trajectory
from irb140_dynamics.identification.excitation import Limits, shaped
from irb140_dynamics.tools import excitation, identify, retime

from ..core.test_urdf_trees import TWO_ARMS, _without_mimics
from ..support.paths import URDF_DATA
from ..support.simulated_ur5 import write_csv

BAXTER = URDF_DATA / "baxter.urdf"
RATE = 500.0  # Hz: the simulation and the recording
PERIODS = 3


def run(capsys, tool, *args):
    status = tool.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def true_tree(model: RobotModel) -> RobotModel:
    """``model`` with each link's mass (and inertia) scaled within [0.7, 1.3], viscous and
    Coulomb friction and armature on every joint: the arm the recording is made on."""
    factors = np.random.default_rng(5).uniform(0.7, 1.3, len(model.joints))
    joints = tuple(
        replace(
            j,
            link=RigidBody(j.link.mass * f, j.link.com, tuple(f * x for x in j.link.inertia)),
            friction=Friction(0.4, 0.2),
            armature=0.03,
        )
        for j, f in zip(model.joints, factors)
    )
    return replace(model, joints=joints)


def record(true: RobotModel, path: Path, order) -> Path:
    """The true tree under computed torque along the excitation file (as the controller
    interpolates it), ``PERIODS`` times; the CSV's columns in ``order``."""
    from irb140_dynamics.sim.engine import SimulatedArm

    sp = spline(Trajectory.from_message(read_joint_trajectory(path), true.joint_names))
    period = float(sp.end)
    t = np.arange(int(round(PERIODS * period * RATE))) / RATE
    Q_ref, QD_ref, QDD_ref = sp.evaluate(np.mod(t, period))
    feed_forward = rnea_batch(true, Q_ref, QD_ref, QDD_ref)
    sim = SimulatedArm(true, period=1.0 / RATE, substeps=2)
    sim.reset(Q_ref[0], QD_ref[0])
    scale = np.diag(mass_matrix(true, Q_ref[0]))  # kg m^2: the feedback through each joint's inertia
    Q, QD, TAU = (np.empty_like(Q_ref) for _ in range(3))
    for k in range(len(t)):
        q, qd = sim.q, sim.qd
        sim.step(feed_forward[k] + scale * (400.0 * (Q_ref[k] - q) + 40.0 * (QD_ref[k] - qd)))
        Q[k], QD[k], TAU[k] = q, qd, sim.applied
    assert np.abs(Q - Q_ref).max() < 0.01  # it followed the excitation
    names = [true.joint_names[i] for i in order]
    return write_csv(path.with_suffix(".csv"), names, t, Q[:, order], QD[:, order], TAU[:, order])


def other_motion(model: RobotModel):
    """(Q, QD, QDD) of a random Fourier motion the recording did not contain."""
    limits = Limits(np.full(model.n, -1.5), np.full(model.n, 1.5), np.full(model.n, 1.5), np.full(model.n, 4.0))
    free = np.random.default_rng(11).normal(size=2 * model.n * 3)
    return shaped(free, model.n, 4, 6.0, limits).evaluate(np.arange(0.0, 6.0, 0.01))


def errors_on_another_motion(true: RobotModel, prior: RobotModel, identified: RobotModel):
    """(identified, prior): each joint's RMS torque error against the true arm's on
    ``other_motion``, over that joint's peak torque; and the motion's positions."""
    Q, QD, QDD = other_motion(prior)
    truth = rnea_batch(true, Q, QD, QDD)
    peak = np.abs(truth).max(axis=0)
    error, before = (
        np.sqrt(np.mean((rnea_batch(m, Q, QD, QDD) - truth) ** 2, axis=0)) / peak for m in (identified, prior)
    )
    print(f"RMS torque error / peak on another motion: prior {np.round(before, 3)}, identified {np.round(error, 3)}")
    return error, before, Q


def test_identify_fits_a_whole_tree_from_one_recording_of_its_excitation(tmp_path, capsys):
    urdf = tmp_path / "two_arms.urdf"
    urdf.write_text(_without_mimics(TWO_ARMS))
    prior = load_urdf(urdf.read_text()).model
    assert not prior.is_chain and prior.n == 7
    excitation_file = tmp_path / "excitation.yaml"
    status, _, err = run(
        capsys, excitation, "--urdf", urdf, "--out", excitation_file, "--iterations", 2, "--period", 6, "--harmonics", 3
    )
    assert status == 0, err
    true = true_tree(prior)
    order = np.random.default_rng(2).permutation(prior.n)
    recording = record(true, excitation_file, order)
    out = tmp_path / "identified.yaml"
    status, printed, err = run(capsys, identify, recording, "--urdf", urdf, "--out", out, "--quiet")
    assert status == 0, err
    assert "the tree below base" in printed
    identified = RobotModel.from_params(read_parameter_file(out))
    assert identified.joint_names == prior.joint_names and identified.parent == prior.parent
    error, before, Q = errors_on_another_motion(true, prior, identified)
    assert np.all(error <= 0.1), error
    assert np.sqrt(np.mean(error**2)) * 3 <= np.sqrt(np.mean(before**2))
    back = load_urdf((tmp_path / "identified.urdf").read_text()).model  # the identified tree as URDF:
    assert back.parent == prior.parent  # its inertials (a URDF holds no armature nor Coulomb friction)
    np.testing.assert_allclose(gravity_batch(back, Q), gravity_batch(identified, Q), rtol=1e-6, atol=1e-6)


def gravity_batch(model: RobotModel, Q) -> np.ndarray:
    return np.array([gravity(model, q) for q in Q[::10]])


def baxter_trajectory(path: Path, model: RobotModel, duration: float) -> tuple[Path, np.ndarray]:
    """A rest-to-rest JointTrajectory of Baxter's joints in a shuffled order, arms from a
    pose where their shoulders hold well within their limits."""
    rng = np.random.default_rng(1)
    order = rng.permutation(model.n)
    start = np.zeros(model.n)
    for name, value in (("right_s1", -0.8), ("left_s1", -0.8), ("right_e1", 1.5), ("left_e1", 1.5)):
        start[model.joint_names.index(name)] = value
    end = start + rng.uniform(-0.3, 0.3, model.n)
    sec = int(duration)
    points = [
        {
            "positions": [float(q[i]) for i in order],
            "velocities": [0.0] * model.n,
            "time_from_start": {"sec": s, "nanosec": ns},
        }
        for q, (s, ns) in ((start, (0, 0)), (end, (sec, int(round((duration - sec) * 1e9)))))
    ]
    path.write_text(yaml.safe_dump({"joint_names": [model.joint_names[i] for i in order], "points": points}))
    return path, order


def test_retime_checks_the_torques_of_a_tree_as_the_cores_rnea(tmp_path, capsys):
    model = load_urdf(BAXTER.read_text()).model
    assert model.mimics is not None and not model.is_chain
    path, _ = baxter_trajectory(tmp_path / "slow.yaml", model, 3.0)
    status, printed, err = run(capsys, retime, "--urdf", BAXTER, "--check-only", path)
    assert status == 0, err + printed
    assert "input: 3.0000 s, within every limit" in printed
    tr = Trajectory.from_message(read_joint_trajectory(path), model.joint_names)
    sp = spline(tr)
    report = check_trajectory(model, tr)
    t = np.linspace(0.0, sp.end, 301)
    tau = rnea_batch(model, *sp.evaluate(t))  # the core's torques along the interpolation
    for j, name in enumerate(model.joint_names):
        peak = next(p for p in report.peaks if p.joint == name and p.quantity == "torque")
        at = rnea_batch(model, *sp.evaluate(np.array([peak.time])))[0, j]
        assert peak.value == pytest.approx(at, rel=1e-12, abs=1e-12)
        assert abs(peak.value) >= np.abs(tau[:, j]).max() - 1e-9
        assert f"{name} torque: {peak.value:+.4g} N m" in printed  # the tool printed the core's number
    right_s1 = model.joint_names.index("right_s1")
    assert np.abs(tau[:, right_s1]).max() > 10.0  # the shoulder holds the arm: the numbers are not trivial


def test_retime_reports_a_tree_trajectory_over_a_torque_limit(tmp_path, capsys):
    model = load_urdf(BAXTER.read_text()).model
    path, _ = baxter_trajectory(tmp_path / "fast.yaml", model, 0.15)
    status, printed, err = run(capsys, retime, "--urdf", BAXTER, "--check-only", path)
    assert status == retime.OVER_LIMIT, err + printed
    report = check_trajectory(model, Trajectory.from_message(read_joint_trajectory(path), model.joint_names))
    worst = report.worst
    assert worst.quantity == "torque" and worst.ratio > 1.0
    assert f"OVER A LIMIT (worst: {worst.line()})" in printed
    status, printed, err = run(capsys, retime, "--urdf", BAXTER, path, tmp_path / "out.yaml")
    assert status == 0, err
    out = Trajectory.from_message(read_joint_trajectory(tmp_path / "out.yaml"), model.joint_names)
    after = check_trajectory(model, out)
    assert after.ok and after.duration > 0.15


def test_retime_payload_mass_on_a_tree_loads_the_named_link_as_the_cores_rnea(tmp_path, capsys):
    """--payload-mass with -p payload.link:=la2 on TWO_ARMS (mimic fingers and all): the
    peaks reported are the core's rnea of the tree carrying the mass at la2's origin, and
    differ from the bare tree's; with no link named, refused in one line."""
    urdf = tmp_path / "two_arms.urdf"
    urdf.write_text(TWO_ARMS)
    loaded = load_urdf(TWO_ARMS)
    bare = loaded.model
    start, end = np.full(bare.n, 0.2), np.full(bare.n, 0.6)
    points = [
        {"positions": start.tolist(), "velocities": [0.0] * bare.n, "time_from_start": {"sec": 0, "nanosec": 0}},
        {"positions": end.tolist(), "velocities": [0.0] * bare.n, "time_from_start": {"sec": 2, "nanosec": 0}},
    ]
    path = tmp_path / "motion.yaml"
    path.write_text(yaml.safe_dump({"joint_names": list(bare.joint_names), "points": points}))
    args = ("--urdf", urdf, "--check-only", "--payload-mass", 0.8, path)
    status, printed, err = run(capsys, retime, *args[:-1], "-p", "payload.link:=la2", path)
    assert status == 0, err + printed
    loaded_model = loaded.with_flange_at("la2").with_payload(RigidBody(0.8))
    tr = Trajectory.from_message(read_joint_trajectory(path), bare.joint_names)
    report, without = check_trajectory(loaded_model, tr), check_trajectory(bare, tr)
    for j, name in enumerate(bare.joint_names):
        peak = next(p for p in report.peaks if p.joint == name and p.quantity == "torque")
        at = rnea_batch(loaded_model, *spline(tr).evaluate(np.array([peak.time])))[0, j]
        assert peak.value == pytest.approx(at, rel=1e-12, abs=1e-12)
        assert f"{name} torque: {peak.value:+.4g} N m" in printed
    peak_of = {p.joint: p.value for p in without.peaks if p.quantity == "torque"}
    l1 = next(p.value for p in report.peaks if p.joint == "l1" and p.quantity == "torque")
    assert abs(l1 - peak_of["l1"]) > 0.5  # the payload loads the left arm
    status, printed, err = run(capsys, retime, *args)
    assert status == 1 and not printed
    assert err.count("\n") == 1 and "--payload-mass: the model is a tree" in err and "payload.link" in err
    status, printed, err = run(
        capsys, retime, *args[:-1], "-p", "payload.link:=la2", "-p", "torso.torque_limit:=0", path
    )
    assert status == 1 and err.count("\n") == 1 and "torso: no torque_limit, and on a tree none is derived" in err
