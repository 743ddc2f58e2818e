"""The retime tool: re-times a JointTrajectory file (joints in any order), checks one, and
refuses bad input in one line, exit status 1, nothing written."""

import math
import subprocess
import sys

import numpy as np
import pytest

from irb140_dynamics.core import irb140
from irb140_dynamics.core.io.trajectory_file import joint_trajectory_yaml
from irb140_dynamics.core.trajectories import Trajectory
from irb140_dynamics.tools.retime import OVER_LIMIT, main

from ..support.common import load_yaml
from ..support.paths import CONFIG, ROOT
from ..support.trajectories import smooth_trajectory

Q0 = np.array([0.0, -0.3, 0.5, 0.0, 0.3, 0.0])
AMPLITUDE = np.array([1.5, 0.6, 0.7, 2.0, 1.2, 2.5])
ORDER = [3, 0, 5, 1, 4, 2]  # the file's joint order


def _message(points=20, duration=4.0):
    tr = smooth_trajectory(irb140().joint_names, Q0, AMPLITUDE * 0.5, points=points, duration=duration)
    message = tr.to_message()
    message["joint_names"] = [message["joint_names"][i] for i in ORDER]
    for point in message["points"]:
        for field in ("positions", "velocities", "accelerations"):
            point[field] = [point[field][i] for i in ORDER]
    return tr, message


def _write(path, message):
    path.write_text(joint_trajectory_yaml(message) + "---\n")  # as ros2 topic echo --once ends
    return str(path)


@pytest.mark.slow  # the first re-timing compiles the kernels; the plot imports matplotlib
def test_retime_writes_the_retimed_trajectory_and_the_plot(tmp_path, capsys):
    tr, message = _message()
    source = _write(tmp_path / "in.yaml", message)
    out, plot = tmp_path / "out.yaml", tmp_path / "plot.png"
    assert main(["--params-file", str(CONFIG), "--payload-mass", "6", source, str(out), "--plot", str(plot)]) == 0
    printed = capsys.readouterr().out
    assert "derived" in printed and "re-timed:" in printed and "within every limit" in printed
    result = Trajectory.from_message(load_yaml(out.read_text()), irb140().joint_names)
    knots = [np.flatnonzero((result.q == q).all(axis=1))[0] for q in tr.q]
    assert knots == sorted(knots) and knots[0] == 0 and knots[-1] == len(result.t) - 1  # same points, in order
    assert result.duration < tr.duration and result.has_qd.all()
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.yaml", "out.yaml", "plot.png"]


def test_check_only_says_whether_the_trajectory_keeps_the_limits(tmp_path, capsys):
    _, message = _message(duration=4.0)
    source = _write(tmp_path / "slow.yaml", message)
    assert main(["--check-only", "--params-file", str(CONFIG), source]) == 0
    _, fast = _message(duration=0.4)
    source = _write(tmp_path / "fast.yaml", fast)
    assert main(["--check-only", "--params-file", str(CONFIG), source]) == OVER_LIMIT
    assert "OVER A LIMIT" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fast.yaml", "slow.yaml"]


def _bad(case):
    _, message = _message(points=6)
    points = message["points"]
    if case == "times":
        points[3]["time_from_start"] = dict(points[2]["time_from_start"])
    elif case == "unknown":
        message["joint_names"][2] = "joint_7"
    elif case == "positions":
        points[4]["positions"] = []
    elif case == "nan":
        points[1]["velocities"][0] = math.nan
    return message


BAD = {  # case: (payload, what the one line says)
    "times": (None, "point 3: time_from_start .* is not after point 2"),
    "unknown": (None, "unknown joint.*joint_7"),
    "positions": (None, "point 4: no positions"),
    "nan": (None, "point 1: velocities of joint_4 is nan"),
    "infeasible": (
        "60",
        r"infeasible path: joint_\d needs [\d.]+ N m .*point.* over its torque limit .* by [\d.]+ N m",
    ),
    "negative payload": ("-1", "--payload-mass: must be a mass >= 0 kg"),
    "nan payload": ("nan", "--payload-mass: must be a mass >= 0 kg"),
    "absurd payload": ("1e9", "--payload-mass: .*mass"),
}


@pytest.mark.parametrize("case", BAD)
def test_bad_input_is_one_line_exit_1_and_nothing_written(case, tmp_path, capsys):
    payload, reason = BAD[case]
    source = _write(tmp_path / "in.yaml", _bad(case))
    args = ["--params-file", str(CONFIG), source, str(tmp_path / "out.yaml"), "--plot", str(tmp_path / "p.png")]
    assert main(args + (["--payload-mass", payload] if payload else [])) == 1
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("retime: error: ")
    assert __import__("re").search(reason, lines[0]), lines[0]
    assert [p.name for p in tmp_path.iterdir()] == ["in.yaml"]


@pytest.mark.process
def test_runs_as_a_module_without_ros(tmp_path):
    _, message = _message(points=8)
    source = _write(tmp_path / "in.yaml", message)
    code = (
        "import sys, runpy\n"
        "sys.modules['rclpy'] = None  # importing rclpy now fails\n"
        f"sys.argv = ['retime', '--params-file', {str(CONFIG)!r}, {source!r}, {str(tmp_path / 'out.yaml')!r}]\n"
        "runpy.run_module('irb140_dynamics.tools.retime', run_name='__main__')\n"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out.yaml").exists()


@pytest.mark.slow  # the UR5's kernels compiled, several rounds
def test_a_urdf_arm_with_the_params_files_globals(tmp_path, capsys):
    from irb140_dynamics.core.urdf import load_urdf

    urdf = ROOT / "test" / "data" / "urdf" / "ur5.urdf"
    model = load_urdf(urdf.read_text(), tip_link="tool0").model
    tr = smooth_trajectory(model.joint_names, np.array([0.0, -1.2, 1.0, -1.0, 0.5, 0.0]), np.full(6, 0.5), 12, 4.0)
    source = _write(tmp_path / "in.yaml", tr.to_message())
    out = tmp_path / "out.yaml"
    params = tmp_path / "globals.yaml"  # what a URDF's model takes from a params file: no IRB-140 joints
    params.write_text(
        "/**:\n  ros__parameters:\n    gravity: [0.0, 0.0, -9.81]\n    friction: {smoothing_velocity: 0.02}\n"
    )
    args = ["--params-file", str(params), "--urdf", str(urdf), "--tip", "tool0", "--payload-mass", "3"]
    assert main([*args, source, str(out)]) == 0
    printed = capsys.readouterr().out
    assert "re-timed:" in printed and "within every limit" in printed and "derived" not in printed  # URDF efforts
    result = Trajectory.from_message(load_yaml(out.read_text()), model.joint_names)
    assert result.duration < tr.duration


def test_the_chain_is_named_with_base_and_tip_as_in_the_other_tools_or_the_old_names():
    from irb140_dynamics.tools.retime import parser

    new = parser().parse_args(["in.yaml", "--params-file", "p.yaml", "--base", "b", "--tip", "t"])
    old = parser().parse_args(["in.yaml", "--params-file", "p.yaml", "--base-link", "b", "--tip-link", "t"])
    assert (new.base, new.tip) == (old.base, old.tip) == ("b", "t")
