"""The calibrate_collision tool: what it reads (CSV or bag, the arm as every tool reads it),
what it prints and writes, and what it refuses.

The recordings are the IRB-140 along a normal motion, torques by RNEA on the model itself
with 1 % noise of each joint's peak (``support.synthetic_arm.drive``): the residual is then
the noise through the observer's lag. What the tool writes is checked against the observer
run here sample by sample (``MomentumObserver``, as id_node runs it) and the printed forces
against each recorded pose's ``detectable_force_at``. The simulated arms, pushed:
test_calibrate_collision_sim.py.
"""

import math
import re

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from irb140_dynamics.core import irb140
from irb140_dynamics.core.io.params_file import read_parameter_file
from irb140_dynamics.core.monitoring.observer import MomentumObserver
from irb140_dynamics.core.monitoring.sensitivity import AXES, detectable_force_at
from irb140_dynamics.tools import calibrate_collision

from ..support.paths import CONFIG
from ..support.simulated_pushes import normal_motion
from ..support.simulated_pushes import write_csv as write_full_csv
from ..support.synthetic_arm import drive, joint_state_messages, write_bag, write_csv

UNIT = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


@pytest.fixture(scope="module")
def samples():
    model = irb140()
    return model, drive(model, normal_motion(model, 7), 250.0, 6.0)


@pytest.fixture(scope="module")
def csv(samples, tmp_path_factory):
    model, s = samples
    path = tmp_path_factory.mktemp("csv") / "run.csv"  # every digit: the same numbers as the bag's
    return write_full_csv(path, model.joint_names, s.time, s.position, s.velocity, s.effort)


def calibrate(capsys, *argv):
    status = calibrate_collision.main([*map(str, argv), "--quiet"])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def thresholds_in(path, model):
    values = read_parameter_file(path)
    return values["collision.observer_gain"], np.array([values[f"{n}.collision_threshold"] for n in model.joint_names])


def observed_peaks(model, s, gain):
    observer = MomentumObserver(model, gain, 0.1)  # id_node's gap (test_the_defaults_and_ranges_are_id_node_s)
    return np.max(
        [np.abs(observer.advance(t, q, qd, tau)) for t, q, qd, tau in zip(s.time, s.position, s.velocity, s.effort)],
        axis=0,
    )


def test_thresholds_are_the_margin_over_id_node_s_residual_and_the_forces_the_worst_pose_s(
    samples, csv, tmp_path, capsys
):
    model, s = samples
    out = tmp_path / "collision.yaml"
    status, printed, err = calibrate(capsys, csv, "--out", out)
    assert status == 0 and err == "", err
    gain, thresholds = thresholds_in(out, model)
    assert gain == 100.0
    assert thresholds == pytest.approx(1.5 * observed_peaks(model, s, 100.0), rel=1e-12)
    lines = {axis: re.search(rf"^{re.escape(axis)}: (\S+) N \(worst pose at (\S+) s", printed, re.M) for axis in AXES}
    for axis, found in lines.items():
        each = [detectable_force_at(model, q, thresholds, UNIT[axis[1]]) for q in s.position]
        worst = max(each)
        shown = float(found.group(1))
        assert worst <= shown <= worst * (1 + 1e-2)  # rounded up to 3 digits: what is printed is detected
        assert float(found.group(2)) == pytest.approx(s.time[int(np.argmax(each))] - s.time[0], abs=1e-3)
    assert all(float(at) < s.time[-1] for at in re.findall(r" at (\S+) s", printed))  # from the start
    assert lines["+x"].group(1) == lines["-x"].group(1)  # thresholds on |r|: a direction and its opposite alike
    assert printed.strip().endswith(f"wrote {out}")
    assert "# +z: " in out.read_text()  # the summary travels with the file


def test_margin_and_gain_are_the_user_s(samples, csv, tmp_path, capsys):
    model, s = samples
    out = tmp_path / "c.yaml"
    assert calibrate(capsys, csv, "--out", out, "--margin", "3", "--observer-gain", "40")[0] == 0
    gain, thresholds = thresholds_in(out, model)
    assert gain == 40.0 and thresholds == pytest.approx(3.0 * observed_peaks(model, s, 40.0), rel=1e-12)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_bag_gives_what_its_csv_gives(samples, csv, tmp_path, capsys, storage):
    model, s = samples
    typestore = get_typestore(Stores.ROS2_JAZZY)
    bag = write_bag(tmp_path / "bag", joint_state_messages(s, model.joint_names, True, typestore), storage=storage)
    from_csv, from_bag = tmp_path / "csv.yaml", tmp_path / "bag.yaml"
    assert calibrate(capsys, csv, "--out", from_csv)[0] == 0
    assert calibrate(capsys, bag, "--out", from_bag, "--params-file", CONFIG)[0] == 0
    # the bag's stamps are read as id_node reads them, seconds since 1970 in a double: 0.2 us
    # off in a 4 ms step, 1e-4 of the observer's
    assert thresholds_in(from_bag, model)[1] == pytest.approx(thresholds_in(from_csv, model)[1], rel=3e-4)


def test_a_recording_without_velocities_is_refused_in_one_line(samples, tmp_path, capsys):
    model, s = samples
    path = write_csv(tmp_path / "no_qd.csv", s, model.joint_names, with_velocity=False)
    out = tmp_path / "c.yaml"
    status, printed, err = calibrate(capsys, path, "--out", out)
    assert status == 1 and printed == "" and not out.exists()
    assert err.count("\n") == 1 and "no sample has velocities" in err and err.startswith("calibrate_collision: error:")


@pytest.mark.parametrize(
    "argv, status, words",
    [
        (["{csv}", "--out", "{csv}"], 1, "would replace the input"),
        (["{csv}", "--out", "{config}"], 1, "would replace the input"),
        (["{csv}", "--out", "{tmp}/c.yaml", "--margin", "1"], 2, "--margin: must be > 1"),
        (["{csv}", "--out", "{tmp}/c.yaml", "--margin", "nan"], 2, "must be a finite number"),
        (["{csv}", "--out", "{tmp}/c.yaml", "--observer-gain", "2e4"], 2, "must be <= 10000"),
        (["{tmp}/none.csv", "--out", "{tmp}/c.yaml"], 1, "no such file"),
        (["{csv}", "--out", "{tmp}/c.yaml", "-p", "joint_2.collision_treshold:=3.0"], 2, "did you mean"),
    ],
)
def test_bad_input_one_line_nothing_written(csv, tmp_path, capsys, argv, status, words):
    before = csv.read_text()
    filled = [a.format(csv=csv, tmp=tmp_path, config=CONFIG) for a in argv]
    found, printed, err = calibrate(capsys, *filled)
    assert found == status and printed == "" and err.count("\n") == 1 and words in err, err
    assert csv.read_text() == before and not (tmp_path / "c.yaml").exists()


def test_rounded_up_never_shows_less_than_the_force():
    for value in (9.1, 9.104, 0.012345, 123.456, 1234.5, 99.99, 1e-4):
        shown = calibrate_collision.rounded_up(value)
        assert float(shown) >= value and float(shown) <= value * 1.01 + 1e-12
        assert len(shown.replace(".", "").lstrip("0")) >= 3 or math.floor(math.log10(value)) >= 2


@pytest.mark.ros  # the node's parameters, or record's ROS side: rclpy
def test_the_defaults_and_ranges_are_id_node_s():
    from irb140_dynamics.core.monitoring import collision
    from irb140_dynamics.nodes.id_node.settings import NODE_PARAMETERS

    gain = next(spec for spec in NODE_PARAMETERS if spec.name == "collision.observer_gain")
    assert (gain.default, gain.minimum, gain.maximum) == (
        collision.DEFAULT_GAIN,
        collision.MIN_GAIN,
        collision.MAX_GAIN,
    )
    assert calibrate_collision.parser().get_default("observer_gain") in (None, collision.DEFAULT_GAIN)


def test_hostile_command_lines_fail_in_one_line_and_leave_nothing(tmp_path):
    """Every bad value of the tools' fuzzing pools (test/support/tool_fuzz.py) in each of
    the tool's arguments, one at a time, the others good."""
    from ..support.tool_fuzz import (
        INPUTS_BAD,
        NUMBERS_BAD,
        OUTPUTS_BAD,
        PARAMS_BAD,
        TOPICS_BAD,
        Case,
        check,
        prepare,
        run_case,
        snapshot,
    )

    prepare(tmp_path)
    good = {"recording": "rest.csv", "--out": "out.yaml", "--params-file": "params.yaml"}
    bad = {
        "recording": INPUTS_BAD,
        "--out": OUTPUTS_BAD,
        "--margin": [*NUMBERS_BAD, "1", "0.5"],
        "--observer-gain": [*NUMBERS_BAD, "0", "1e5"],
        "--topic": TOPICS_BAD,
        "-p": PARAMS_BAD,
        "--params-file": ["missing.yaml", "binary.csv", "/dev/zero", "folder", "absurd.csv"],
    }
    problems = []
    for name, values in bad.items():
        for value in values:
            given = {**good, name: value}
            argv = [given.pop("recording")] + [x for option, v in given.items() for x in (option, v)]
            case = Case("calibrate_collision", [*argv, "--quiet"])
            before = snapshot(tmp_path)
            status, out, err = run_case(case, tmp_path)
            problem = check(case, status, out, err, before, snapshot(tmp_path))
            if problem or status == 0:  # rest.csv has no velocities: nothing succeeds
                problems.append(f"{argv}: {problem or 'succeeded'}")
    assert not problems, "\n".join(problems)


def test_a_direction_no_joint_feels_is_named_not_given_a_figure(tmp_path, capsys):
    """An arm that turns about z and slides and turns in the plane feels no force along z:
    those lines say so, the others have figures; the sliding joint's unit is N."""
    from irb140_dynamics.core.urdf import load_urdf

    from ..support.paths import URDF_DATA

    urdf = URDF_DATA / "prismatic_arm.urdf"
    model = load_urdf(urdf.read_text()).model
    s = drive(model, normal_motion(model, 2), 250.0, 4.0)
    path = write_full_csv(tmp_path / "run.csv", model.joint_names, s.time, s.position, s.velocity, s.effort)
    status, printed, err = calibrate(capsys, path, "--urdf", urdf, "--out", tmp_path / "c.yaml")
    assert status == 0, err
    assert re.search(r"^\+z: none: at 1000 recorded poses \(the first at 0\.000 s\) no joint feels", printed, re.M)
    assert re.search(r"^-x: \d", printed, re.M) and re.search(r"^  reach: largest \|r\| \S+ N at ", printed, re.M)
