"""The load identification commands: `excitation --payload` -> a recording -> `identify
--payload-only` -> a params file whose payload.inertia `retime` and the trajectory check use.

The recording is the IRB-140 of config/true_arm.yaml (friction, rotor inertia) carrying a
payload along the points the command wrote, its torques by our RNEA with 1 % noise of each
joint's peak (the MuJoCo-simulated arms: test/identification/test_payload_identification.py).
"""

import re

import numpy as np
import pytest

from irb140_dynamics.core import RigidBody, rnea_batch
from irb140_dynamics.core.io.params_file import load_model, read_parameter_file
from irb140_dynamics.core.trajectories import Trajectory, check_trajectory
from irb140_dynamics.tools import excitation as excitation_tool
from irb140_dynamics.tools import identify as identify_tool
from irb140_dynamics.tools import retime as retime_tool

from ..support.common import load_yaml
from ..support.paths import CONFIG, ROOT
from ..support.simulated_ur5 import write_csv

pytestmark = pytest.mark.slow  # optimises an excitation and identifies a payload
ARM = ROOT / "config" / "true_arm.yaml"
PAYLOAD = RigidBody(3.0, (0.05, 0.03, 0.08), (0.02, 0.03, 0.015, 0.004, -0.002, 0.003))


def points_of(path):
    document = load_yaml(path.read_text())
    t = np.array([p["time_from_start"]["sec"] + 1e-9 * p["time_from_start"]["nanosec"] for p in document["points"]])
    fields = ("positions", "velocities", "accelerations")
    return document, t, *(np.array([p[f] for p in document["points"]]) for f in fields)


@pytest.fixture(scope="module")
def workflow(tmp_path_factory):
    work = tmp_path_factory.mktemp("load")
    motion = work / "payload_motion.yaml"
    arguments = ["--payload", "--params-file", str(ARM), "--out", str(motion), "--iterations", "5"]
    assert excitation_tool.main([*arguments, "--period", "10", "--periods", "2", "--rate", "100"]) == 0
    document, t, Q, QD, QDD = points_of(motion)
    arm = load_model(ARM)
    tau = rnea_batch(arm.with_payload(PAYLOAD), Q, QD, QDD)
    measured = tau + np.random.default_rng(4).normal(size=tau.shape) * 0.01 * np.abs(tau).max(axis=0)
    recording = write_csv(work / "recording.csv", arm.joint_names, t, Q, QD, measured)
    load = work / "load.yaml"
    return work, motion, (t, Q, QD, QDD), recording, load


@pytest.fixture(scope="module")
def identified(workflow):
    work, _, _, recording, load = workflow
    assert identify_tool.main(["--payload-only", "--params-file", str(ARM), str(recording), "--out", str(load)]) == 0
    return load_model(load)


def test_the_payload_motion_is_the_wrist_within_limits_and_30_s(workflow):
    _, motion, (t, Q, QD, QDD), _, _ = workflow
    text = motion.read_text()
    assert "condition number of the payload's noise-weighted regressor" in text and "identify --payload-only" in text
    assert "# expected at an effort noise of 1 % of each joint's torque limit" in text
    assert re.search(r"#   mass \+- \S+ kg, m\*cx \+- \S+ kg m, .*Izz \+- \S+ kg m\^2", text)
    assert t[-1] <= 30.0 and t[-1] == pytest.approx(20.0)
    assert np.all(np.ptp(Q[:, 3:], axis=0) > 0.1) and np.all(np.ptp(Q[:, :3], axis=0) <= 0.02)
    arm = load_model(ARM)
    lower, upper = np.array([j.position_limits for j in arm.joints]).T
    assert np.all((lower <= Q) & (upper >= Q))
    assert np.all(np.abs(QD) <= [j.velocity_limit for j in arm.joints])
    assert np.all(np.abs(QDD) <= [j.acceleration_limit for j in arm.joints])
    assert np.all(QD[0] == 0) and np.all(QD[-1] == 0)


def test_identify_payload_only_prints_values_with_deviations_and_writes_the_arm_with_them(workflow, identified, capsys):
    _, _, _, _, load = workflow
    payload = identified.payload
    assert payload.mass == pytest.approx(PAYLOAD.mass, rel=0.02)
    assert np.linalg.norm(np.subtract(payload.com, PAYLOAD.com)) < 0.005
    assert payload.inertia == pytest.approx(PAYLOAD.inertia, abs=0.002)
    arm = load_model(ARM)
    assert identified.joints == arm.joints  # the arm's own parameters as they were
    text = load.read_text()
    for label in ("mass", "com.x", "com.y", "com.z", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"):
        assert any(line.startswith(f"#   {label} ") and "+-" in line for line in text.splitlines()), label


@pytest.mark.ros  # trajectory_check_node's settings: ROS's messages
def test_retime_and_the_trajectory_check_use_the_identified_inertia(workflow, identified, capsys):
    """`retime --check-only --params-file LOAD.yaml` prints the torques of the identified
    payload, inertia included (not those of the same mass and CoM without it), and the
    trajectory check node's settings take the file's payload whole."""
    from irb140_dynamics.nodes.trajectory_check_node.node import draft

    _, motion, _, _, load = workflow
    trajectory = Trajectory.from_message(load_yaml(motion.read_text()), identified.joint_names)
    point_mass = identified.with_payload(RigidBody(identified.payload.mass, identified.payload.com))
    torques = [p for p in check_trajectory(identified, trajectory).peaks if p.quantity == "torque"]
    without = [p for p in check_trajectory(point_mass, trajectory).peaks if p.quantity == "torque"]
    assert any(abs(a.value - b.value) > 1e-3 * abs(a.value) for a, b in zip(torques, without))
    capsys.readouterr()
    assert retime_tool.main(["--check-only", "--params-file", str(load), str(motion)]) in (0, 3)
    printed = capsys.readouterr().out
    assert all(peak.line() in printed for peak in torques), printed
    assert not all(peak.line() in printed for peak in without)
    values = {**read_parameter_file(load), "retime.grid": 1000, "diagnostics.warn_use": 80.0}
    assert draft(values)[0].payload == identified.payload  # the node reads payload.inertia


def test_a_bag_gives_the_same_payload_and_a_previous_payload_in_the_arm_file_is_replaced(
    workflow, identified, tmp_path
):
    """REC as an .mcap bag (positions only: velocities differentiated) and ARM.yaml carrying
    another payload (-p): the same payload within its tolerances."""
    from rosbags.typesys import Stores, get_typestore

    from ..support.synthetic_arm import Samples, joint_state_messages, write_bag

    _, _, _, recording, _ = workflow
    data = np.loadtxt(recording, delimiter=",", skiprows=1)
    t, Q, QD, TAU = data[:, 0], data[:, 1:7], data[:, 7:13], data[:, 13:19]
    names = load_model(ARM).joint_names
    typestore = get_typestore(Stores.ROS2_JAZZY)
    messages = joint_state_messages(Samples(t, Q, QD, TAU, TAU), names, with_velocity=False, typestore=typestore)
    bag = write_bag(tmp_path / "bag", messages)
    out = tmp_path / "load.yaml"
    arguments = ["--payload-only", "--quiet", "--params-file", str(ARM), "-p", "payload.mass:=7.0"]
    assert identify_tool.main([*arguments, str(bag), "--out", str(out)]) == 0
    payload = load_model(out).payload
    assert payload.mass == pytest.approx(PAYLOAD.mass, rel=0.02)
    assert np.linalg.norm(np.subtract(payload.com, PAYLOAD.com)) < 0.005
    assert payload.inertia == pytest.approx(identified.payload.inertia, abs=0.002)


def _at_rest(path, work):
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    data[:, 1:13] = np.r_[data[0, 1:7], np.zeros(6)]
    out = work / "rest.csv"
    np.savetxt(out, data, delimiter=",", header=path.read_text().splitlines()[0], comments="")
    return out


def _without_efforts(path, work):
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    keep = [k for k, name in enumerate(header) if not name.startswith("effort_")]
    out = work / "no_effort.csv"
    out.write_text("\n".join(",".join(line.split(",")[k] for k in keep) for line in lines) + "\n")
    return out


def _last_joint_only(path, work):
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    t, Q, QD = data[:, 0], data[:, 1:7], data[:, 7:13]
    Q[:, :5], QD[:, :5] = Q[0, :5], 0.0
    QDD = np.gradient(QD, t, axis=0)
    tau = rnea_batch(load_model(ARM).with_payload(PAYLOAD), Q, QD, QDD)
    return write_csv(work / "last_joint.csv", load_model(ARM).joint_names, t, Q, QD, tau)


def _not_a_recording(path, work):
    out = work / "bad.csv"
    out.write_text("hello\n1,2\n")
    return out


def _changed(name, change):
    """The recording with ``change(data)`` applied to its columns (time, Q, QD, TAU)."""

    def make(path, work):
        data = np.loadtxt(path, delimiter=",", skiprows=1)
        change(data)
        out = work / name
        np.savetxt(out, data, delimiter=",", header=path.read_text().splitlines()[0], comments="")
        return out

    return make


def _scale(columns, factor):
    def change(data):
        data[:, columns] *= factor

    return change


BAD = {
    "missing recording": (lambda rec, work: work / "nowhere.csv", "nowhere.csv"),
    "time stamps in microseconds": (_changed("us.csv", _scale(0, 1e-6)), "check that the time stamps are in seconds"),
    "efforts all zero": (_changed("zero.csv", _scale(slice(13, 19), 0.0)), "no physical payload explains them"),
    "efforts of the other sign": (_changed("sign.csv", _scale(slice(13, 19), -1.0)), "no physical payload explains"),
    "not a recording": (_not_a_recording, "bad.csv"),
    "no efforts": (_without_efforts, "effort"),
    "not exciting": (_last_joint_only, "does not excite the payload's Ixx, Ixy, Iyy"),
    "at rest": (_at_rest, "nothing moves"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_recordings_are_refused_in_one_line_and_nothing_is_written(workflow, tmp_path, capsys, case):
    _, _, _, recording, _ = workflow
    make, problem = BAD[case]
    bad = make(recording, tmp_path)
    model = ["--params-file", str(ARM)]
    out = tmp_path / "load.yaml"
    capsys.readouterr()
    assert identify_tool.main(["--payload-only", "--quiet", *model, str(bad), "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("identify: error: ") and problem in err[0], err
    assert not out.exists()


def test_an_arm_model_without_its_friction_is_refused(workflow, tmp_path, capsys):
    """The designed motion excites the payload so well that such a model's payload (80 % too
    heavy here) would come with small deviations from white noise; the residuals' correlation
    (what the model leaves unexplained changes slowly) raises them honestly, and it is refused:
    by the efforts' scale against the model's torques (the first check), or by those deviations."""
    _, _, _, recording, _ = workflow
    out = tmp_path / "load.yaml"
    model = ["--params-file", str(ROOT / "config/irb140.yaml")]
    assert identify_tool.main(["--payload-only", "--quiet", *model, str(recording), "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    refusals = ("check the arm's parameters (torques its model leaves unexplained)", "and the arm's own parameters")
    assert len(err) == 1 and any(refusal in err[0] for refusal in refusals), err
    assert not out.exists()


@pytest.mark.parametrize(
    "arguments, problem",
    [
        (["--params-file", "nowhere.yaml"], "nowhere.yaml"),
        ([], "--payload-only: give the arm's model"),
        (["--params-file", str(ARM), "--plots", "plots"], "--plots: not with --payload-only"),
        (["--params-file", str(ARM), "--held-out", "0.5"], "--held-out: not with --payload-only"),
        (["--params-file", str(ARM), "--prior-weight", "2"], "--prior-weight: not with --payload-only"),
        (["--params-file", "BADFILE"], "BADFILE"),
    ],
)
def test_bad_model_arguments_are_refused_in_one_line(workflow, tmp_path, capsys, arguments, problem):
    _, _, _, recording, _ = workflow
    bad_params = tmp_path / "bad.yaml"
    bad_params.write_text("/**:\n  ros__parameters:\n    payload: {mass: -1.0}\n")
    arguments = [str(bad_params) if a == "BADFILE" else a for a in arguments]
    problem = "bad.yaml" if problem == "BADFILE" else problem
    out = tmp_path / "load.yaml"
    capsys.readouterr()
    assert identify_tool.main(["--payload-only", "--quiet", *arguments, str(recording), "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and problem in err[0], err
    assert not out.exists()


def test_excitation_payload_refuses_more_than_30_s_and_a_bad_pose(tmp_path, capsys):
    out = tmp_path / "motion.yaml"
    assert excitation_tool.main(["--payload", "--out", str(out), "--period", "20", "--periods", "2"]) == 1
    assert "at most 30 s, got 40 s" in capsys.readouterr().err
    assert excitation_tool.main(["--payload", "--out", str(out), "--pose", "0,3,0,0,0,0", "--iterations", "0"]) == 1
    assert "--pose: joint_2 at 3 rad is outside" in capsys.readouterr().err
    assert excitation_tool.main(["--payload", "--out", str(out), "--pose", "0,0,0,0,0,9", "--iterations", "0"]) == 1
    out_text, err = capsys.readouterr()
    assert "--pose: joint_6 at 9 rad is outside" in err and out_text == ""  # refused before any work
    # forearm straight up (joint_3 at 90 degrees): the wrist's turns cannot tell some parameters apart
    assert (
        excitation_tool.main(["--payload", "--out", str(out), "--pose", "0,0,1.5708,0,0,0", "--iterations", "0"]) == 1
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(
        r"--pose: at this pose the wrist's motion cannot tell the payload's .+ apart", err[0]
    )
    assert "hold another --pose" in err[0], err
    assert excitation_tool.main(["--out", str(out), "--pose", "0,0,0,0,0,0"]) == 1
    assert "--pose: only with --payload" in capsys.readouterr().err
    assert not out.exists()


def test_the_expected_deviations_follow_the_stated_noise_and_rate(tmp_path, capsys):
    """The same motion (same seed) at twice the noise in N m: every deviation doubles; recorded
    at a quarter of the rate: doubles too. Bad noise values are refused in one line."""

    def expected(*options):
        out = tmp_path / "motion.yaml"
        arguments = ["--payload", "--out", str(out), "--iterations", "2", "--period", "5", *options]
        assert excitation_tool.main([*arguments, "--params-file", str(ARM)]) == 0
        printed = capsys.readouterr().out
        values = re.search(r"\n  (mass \+- .+)\n", printed).group(1)
        assert f"#   {values}" in out.read_text()  # the file's header says it too
        return np.array([float(x) for x in re.findall(r"\+- (\S+)", values)])

    base = expected("--effort-noise", "0.05")
    assert len(base) == 10 and np.all(base > 0)
    assert expected("--effort-noise", "0.1") == pytest.approx(2 * base, rel=0.03)  # printed to 2 digits
    assert expected("--effort-noise", "0.05", "--record-rate", "125") == pytest.approx(2 * base, rel=0.03)
    out = tmp_path / "refused.yaml"
    for bad, problem in [("-1", "must be > 0"), ("x", "expected N m"), ("100%", "below 100 %"), ("nan", "must be > 0")]:
        assert excitation_tool.main(["--payload", "--out", str(out), "--effort-noise", bad]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--effort-noise" in err[0] and problem in err[0], err
    assert excitation_tool.main(["--out", str(out), "--effort-noise", "1%"]) == 1
    assert "--effort-noise: only with --payload" in capsys.readouterr().err
    assert not out.exists()


def test_the_load_file_of_a_urdf_arm_says_how_the_nodes_take_it(tmp_path):
    """The nodes declare DH joints only: a URDF arm's LOAD.yaml (origin/axis joints) is for the
    tools; its comment tells how the nodes take the payload (the arm from the URDF)."""
    from irb140_dynamics.core.io.arm_source import given_values, read_arm, read_urdf_file
    from irb140_dynamics.identification.payload_excitation import optimise_payload_excitation

    from ..support.paths import URDF_DATA

    urdf = ["--urdf", str(URDF_DATA / "ur5.urdf"), "--base", "base_link", "--tip", "tool0"]
    arm = read_arm({}, urdf=read_urdf_file(urdf[1]), base_link="base_link", tip_link="tool0").model
    trajectory = optimise_payload_excitation(arm, iterations=0).trajectory
    t = np.arange(0.0, 2 * trajectory.period, 0.004)
    Q, QD, QDD = trajectory.evaluate(t)
    tau = rnea_batch(arm.with_payload(PAYLOAD), Q, QD, QDD)
    recording = write_csv(tmp_path / "ur5.csv", arm.joint_names, t, Q, QD, tau)
    out = tmp_path / "load.yaml"
    assert identify_tool.main(["--payload-only", "--quiet", *urdf, str(recording), "--out", str(out)]) == 0
    taken = read_arm(given_values([out]), read_parameter_file(CONFIG)).model  # the tools take it
    assert taken.payload.mass == pytest.approx(PAYLOAD.mass, rel=1e-3)
    comments = " ".join(line for line in out.read_text().splitlines() if line.startswith("#"))
    assert "the nodes take this arm from its URDF (model.source: robot_description" in comments
    assert "Load it into the nodes" not in comments


@pytest.mark.parametrize("factor", [1000.0, 2.0])
def test_efforts_not_in_newton_metres_are_refused_naming_their_scale(workflow, tmp_path, capsys, factor):
    """Efforts in N mm (x1000: a payload of tonnes before) or doubled (x2: 40 kg for 3.5 kg):
    a payload cannot scale the torques of the arm's own links, and the fit says by how much."""
    _, _, _, recording, _ = workflow
    scaled = _changed("scaled.csv", _scale(slice(13, 19), factor))(recording, tmp_path)
    out = tmp_path / "load.yaml"
    capsys.readouterr()
    assert (
        identify_tool.main(["--payload-only", "--quiet", "--params-file", str(ARM), str(scaled), "--out", str(out)])
        == 1
    )
    err = capsys.readouterr().err.strip().splitlines()
    found = re.fullmatch(
        r"identify: error: .*scaled\.csv: the efforts are (\S+) \+- (\S+) times the torques of the arm's model: "
        r"check their units \(N m, not N mm\) and sign, and the arm's own parameters \(`identify` it first\)",
        err[0],
    )
    assert len(err) == 1 and found, err
    assert float(found[1]) == pytest.approx(factor, rel=0.01) and float(found[2]) < 0.01 * factor
    assert not out.exists()


def test_a_wrist_without_an_acceleration_limit_is_taken_to_reach_its_speed_in_a_quarter_second(tmp_path, capsys):
    """The UR5's URDF states velocity limits (3.2 rad/s at the wrist) and no acceleration limit:
    the motion uses up to 3.2 / 0.25 = 12.8 rad/s^2 there, says so before anything moves (and
    in the file), and keeps to a limit a params file states instead."""
    from irb140_dynamics.core.io.params_file import parameter_file_text

    from ..support.paths import URDF_DATA

    urdf = ["--urdf", str(URDF_DATA / "ur5.urdf"), "--tip", "tool0", "--pose", "0,-1.2,1.5,0,0,0", "--period", "3"]
    wrist_joints = ("wrist_1_joint", "wrist_2_joint", "wrist_3_joint")

    def peak_accelerations(*arguments):
        out = tmp_path / "motion.yaml"
        assert (
            excitation_tool.main(
                ["--payload", "--iterations", "0", "--rate", "50", *urdf, *arguments, "--out", str(out)]
            )
            == 0
        )
        document = load_yaml(out.read_text())
        QDD = np.array([p["accelerations"] for p in document["points"]])
        return np.abs(QDD).max(axis=0)[3:], capsys.readouterr().out, out.read_text()

    peaks, printed, written = peak_accelerations()
    line = f"no acceleration limit given for {', '.join(wrist_joints)}: assumed 12.8, 12.8, 12.8 rad/s^2"
    assert line in printed and line in written
    assert np.all(peaks <= 12.8 + 1e-6) and peaks.max() > 2 * 5.0  # used, not the old 5 rad/s^2
    stated = tmp_path / "limits.yaml"
    stated.write_text(parameter_file_text({f"{name}.acceleration_limit": 8.0 for name in wrist_joints}, []))
    peaks, printed, _ = peak_accelerations("--params-file", str(stated))
    assert "no acceleration limit given" not in printed
    assert np.all(peaks <= 8.0 + 1e-6)


def test_a_wrist_without_a_velocity_limit_is_said_to_be_designed_at_the_default_speed():
    """A model that states no velocity limit (an MJCF's, as Menagerie's FR3) is designed at
    1 rad/s and 5 rad/s^2 there, and the expectation says so first."""
    from dataclasses import replace

    from irb140_dynamics.core.io.arm_source import read_arm, read_urdf_file
    from irb140_dynamics.identification.payload_excitation import optimise_payload_excitation

    from ..support.paths import URDF_DATA

    arm = read_arm({}, urdf=read_urdf_file(str(URDF_DATA / "ur5.urdf")), tip_link="tool0").model
    arm = replace(arm, joints=tuple(replace(j, velocity_limit=0.0) if k >= 3 else j for k, j in enumerate(arm.joints)))
    design = optimise_payload_excitation(arm, period=3.0, iterations=0, pose=[0.0, -1.2, 1.5, 0.0, 0.0, 0.0])
    lines = design.expectation()
    assert lines[0].startswith(
        "no velocity limit given for wrist_1_joint, wrist_2_joint, wrist_3_joint: assumed 1 rad/s"
    )
    assert lines[1].startswith(
        "no acceleration limit given for wrist_1_joint, wrist_2_joint, wrist_3_joint: assumed 5, 5, 5"
    )
    QD = design.trajectory.evaluate(np.linspace(0.0, 3.0, 3000))[1]
    assert 0.9 < np.abs(QD[:, 3:]).max() <= 1.0
