"""What the tools print, read as a user reads it: a joint without a limit said to have none,
counts with their singular, the URDF chain's ends named by the options the tools take, and
excitation's advice on publishing that works for the file it wrote."""

import pytest

from irb140_dynamics.core.errors import counted
from irb140_dynamics.core.trajectories.check import JointPeak
from irb140_dynamics.tools import equations, excitation, export_urdf, identify, load_diagram, retime

from ..support.paths import CONFIG, ROOT, URDF_DATA

UR5 = str(URDF_DATA / "ur5.urdf")  # three leaves: the chain's tip must be named


def test_a_joint_without_a_limit_is_said_to_have_none(capsys):
    free = JointPeak("joint_1", "torque", -94.16, float("inf"), 1.5, 3)
    assert free.line() == "joint_1 torque: -94.16 N m (no limit) at t = 1.5000 s, segment from point 3"
    limited = JointPeak("joint_2", "torque", 50.0, 100.0, 1.5, -1)
    assert limited.line() == "joint_2 torque: +50 N m of 100 (50.0 %) at t = 1.5000 s, before point 0"
    trajectory = ROOT / "docs" / "trajectory_example.yaml"  # joint_1 and joint_6: no torque limit with 6 kg
    assert retime.main(["--check-only", "--params-file", str(CONFIG), "--payload-mass", "6", str(trajectory)]) == 0
    printed = capsys.readouterr().out
    assert "  joint_1 torque: " in printed and "of none" not in printed, printed
    assert next(line for line in printed.splitlines() if "joint_1 torque" in line).count("(no limit)") == 1


def test_counts_take_the_singular_for_one(tmp_path, capsys):
    assert [counted(k, "point") for k in (0, 1, 2, 1234)] == ["0 points", "1 point", "2 points", "1,234 points"]
    assert load_diagram.main(["--out", str(tmp_path / "o"), "--z-max", "0", "--l-max", "0"]) == 0
    assert capsys.readouterr().out.startswith("load_diagram: 1 point (1 z x 1 l), 1 proven (100.0 %)")


@pytest.mark.parametrize(
    "main, arguments",
    [
        (load_diagram.main, ["--urdf", UR5, "--tip", "nosuch", "--out", "o"]),
        (excitation.main, ["--urdf", UR5, "--tip", "nosuch", "--out", "o.yaml"]),
        (export_urdf.main, ["export_urdf", "--urdf", UR5, "--tip", "nosuch"]),
        (identify.main, ["run.csv", "--urdf", UR5, "--tip", "nosuch", "--out", "o.yaml"]),
        (retime.main, ["--params-file", str(CONFIG), "--urdf", UR5, "--tip", "nosuch", "--check-only", "in.yaml"]),
        (equations.main, ["--urdf", UR5, "--tip", "nosuch", "--form", "c", "--out", "o"]),
    ],
    ids=lambda value: getattr(value, "__module__", "").rsplit(".", 1)[-1] or None,
)
def test_a_chain_end_is_named_by_the_tools_option(main, arguments, tmp_path, capsys, monkeypatch):
    """A tip that is no link of the URDF: the line names --tip (the core's and the nodes'
    name, tip_link, is no option of a tool); a tip the params file names is named as there."""
    monkeypatch.chdir(tmp_path)
    for name in ("run.csv", "in.yaml"):
        (tmp_path / name).write_text("")
    assert main(arguments) == 1
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and f"{UR5}: --tip: no link 'nosuch' in the URDF" in err[0], err
    assert "tip_link" not in err[0]


def test_a_chain_end_from_the_params_file_is_named_as_there(tmp_path, capsys):
    arm = tmp_path / "arm.yaml"
    arm.write_text("/**:\n  ros__parameters:\n    model:\n      tip_link: nosuch\n")
    common = ["--urdf", UR5, "--params-file", str(arm), "--out", str(tmp_path / "o")]
    assert load_diagram.main(common) == 1
    assert ": model.tip_link: no link 'nosuch' in the URDF (links: base_link, " in capsys.readouterr().err
    assert load_diagram.main([*common, "--tip", "tool0", "--base", "nosuch"]) == 1
    assert ": --base: no link 'nosuch' in the URDF (links: base_link, " in capsys.readouterr().err  # a link's name kept


@pytest.mark.parametrize("rate, advice", [(20, '"$(cat FILE)"   (or --yaml-file FILE)'), (500, "--yaml-file FILE")])
def test_excitation_advises_the_way_of_publishing_that_takes_its_file(rate, advice, tmp_path, capsys):
    """Over 128 kB ("$(cat FILE)" is one shell argument, which Linux caps there) the file's
    header names only --yaml-file, as the printed note says."""
    out = tmp_path / "motion.yaml"
    arguments = ["--out", str(out), "--iterations", "0", "--period", "10", "--harmonics", "2", "--rate", str(rate)]
    assert excitation.main(arguments) == 0
    printed = capsys.readouterr().out
    header = [line for line in out.read_text().splitlines() if line.startswith("#")]
    publish = next(line for line in header if "ros2 topic pub" in line)
    assert f"trajectory_msgs/msg/JointTrajectory {advice}" in publish, header
    long = out.stat().st_size > excitation.SHELL_ARGUMENT_LIMIT
    assert long == (rate == 500) and ("$(cat" in publish) == (not long) and ("too long" in printed) == long
