"""The load_diagram tool: the CSV and the PNG of a diagram (a coarse grid), its console
scripts, and bad input refused in one line, exit status non-zero, nothing written."""

import csv
import math
import subprocess
import sys
import warnings

import numpy as np
import pytest

from irb140_dynamics.tools.load_diagram import grid, main

from ..support.paths import CONFIG, ROOT, URDF_DATA

PNG = b"\x89PNG\r\n\x1a\n"


def rows_of(path):
    with open(path, newline="") as stream:
        return list(csv.DictReader(stream))


@pytest.mark.slow  # compiles the kernels and proves a few points; the plot imports matplotlib
def test_writes_the_csv_and_the_png_and_prints_one_line(tmp_path, capsys):
    out = tmp_path / "diagram"
    code = main(["--params-file", str(CONFIG), "--out", str(out), "--z-max", "0.2", "--l-max", "0.1", "--step", "0.1"])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert printed.out.count("\n") == 1 and printed.out.startswith("load_diagram: 6 points (3 z x 2 l), 6 proven")
    rows = rows_of(out / "load_diagram.csv")
    assert list(rows[0]) == ["z_m", "l_m", "max_mass_kg", "status", "limiting_joint", "reason"]
    assert [(float(r["z_m"]), float(r["l_m"])) for r in rows] == [(z, l) for z in (0, 0.1, 0.2) for l in (0, 0.1)]
    assert all(r["status"] == "proven" and r["reason"] == "" and r["limiting_joint"].startswith("joint_") for r in rows)
    masses = np.array([float(r["max_mass_kg"]) for r in rows]).reshape(3, 2)
    assert 5.9 <= masses[0, 0] <= 6.0  # the rated payload at the flange origin: the limits' own case
    assert (np.diff(masses, axis=0) < 0).all() and (np.diff(masses, axis=1) < 0).all()  # further out, less
    assert (out / "load_diagram.png").read_bytes()[:8] == PNG
    assert sorted(p.name for p in out.iterdir()) == ["load_diagram.csv", "load_diagram.png"]


@pytest.mark.slow
def test_a_urdf_arm_with_its_own_effort_limits(tmp_path, capsys):
    out = tmp_path / "ur5"
    urdf = str(URDF_DATA / "ur5.urdf")
    code = main(
        ["--urdf", urdf, "--tip", "tool0", "--out", str(out), "--z-max", "0.1", "--l-max", "0", "--step", "0.1"]
    )
    assert code == 0, capsys.readouterr().err
    rows = rows_of(out / "load_diagram.csv")
    assert len(rows) == 2 and all(r["status"] == "proven" for r in rows)


@pytest.mark.parametrize(
    "mass, code, starts",
    [
        ("2", 0, "load_diagram: inside: 2 kg at Z 0.1 m, L 0.05 m holds in every pose and direction (proven); margin "),
        ("3", 1, "load_diagram: outside: 3 kg at Z 0.1 m, L 0.05 m exceeds joint_4's limit in a pose found; margin -"),
    ],
)
def test_check_says_inside_or_outside_in_one_line(tmp_path, capsys, monkeypatch, mass, code, starts):
    """The IRB-140 at Z 0.1 m, L 0.05 m holds 2.289 kg proven, 2.300 kg at a pose found."""
    monkeypatch.chdir(tmp_path)
    assert main(["--check", mass, "0.1", "0.05"]) == code
    printed = capsys.readouterr()
    assert printed.out.count("\n") == 1 and printed.out.startswith(starts), printed
    assert printed.out.rstrip().endswith("limiting joint joint_4") and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "arguments, says",
    [
        (["--check", "2", "0.1"], "argument --check: expected 3 arguments"),
        (["--check", "-1", "0.1", "0"], "--check -1 0.1 0: MASS must be within 0..1e+06 kg"),
        (["--check", "1", "0.1", "-0.1"], "L (a distance off the axis) within 0..10 m"),
        ([], "the following arguments are required: --out (or --check MASS Z L)"),
    ],
)
def test_a_bad_check_is_a_bad_argument(capsys, arguments, says):
    assert main(arguments) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err


@pytest.mark.parametrize(
    "arguments, says",
    [
        (["--urdf", str(URDF_DATA / "ur5.urdf"), "--tip", "nosuchlink"], "nosuchlink"),
        (["--params-file", "missing.yaml"], "missing.yaml: no such file or directory"),
        (["--urdf", "bad.urdf"], "bad.urdf"),
    ],
)
def test_bad_input_to_a_check_exits_2_not_the_answer_outside(tmp_path, capsys, monkeypatch, arguments, says):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.urdf").write_text("<robot name='x'><link name='a'/>")
    assert main([*arguments, "--check", "1", "0.1", "0.05"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err and "Traceback" not in err, err


def test_the_rated_payload_is_the_arms_own():
    """--rated-mass over rated_payload.mass over nothing stated (the limits then derived
    from the nodes' default, 6 kg at the flange, and no curve marked)."""
    from irb140_dynamics.core.payload import RATED_PAYLOAD
    from irb140_dynamics.tools.load_diagram import rated_payload

    assert rated_payload({}, None) == (RATED_PAYLOAD, False)
    body, stated = rated_payload({"rated_payload.mass": 3.0, "rated_payload.com": [0.0, 0.0, 0.05]}, None)
    assert stated and body.mass == 3.0 and body.com == (0.0, 0.0, 0.05)
    assert rated_payload({"rated_payload.mass": 3.0}, 2.5)[0].mass == 2.5
    with pytest.raises(ValueError, match="rated_payload.mass"):
        rated_payload({"rated_payload.mass": -1.0}, None)


def test_the_grid_holds_both_ends():
    np.testing.assert_allclose(grid(0.3, 0.01), np.arange(31) * 0.01)
    np.testing.assert_allclose(grid(0.25, 0.1), [0.0, 0.1, 0.2, 0.25])
    np.testing.assert_allclose(grid(0.0, 0.1), [0.0])


@pytest.mark.parametrize(
    "arguments, says",
    [
        (["--z-max", "-0.1"], "argument --z-max: must be >= 0, got -0.1"),
        (["--l-max", "nan"], "argument --l-max: must be a finite number"),
        (["--step", "0"], "argument --step: must be > 0, got 0"),
        (["--step", "1e-5"], "--step 1e-05: 30001 x 20001 points, more than 20,000: give a larger step"),
        (["--step", "1e-10"], "--step 1e-10: 3000000001 x 2000000001 points, more than 20,000"),
        (["--step", "5e-324"], "--step 4.94066e-324: too many x too many points, more than 20,000"),
        (["--urdf", "huge_effort.urdf"], 'huge_effort.urdf: URDF joint "shoulder_pan_joint" <limit>: effort must be'),
        (["--params-file", "missing.yaml"], "missing.yaml: no such file or directory"),
        (["--urdf", "bad.urdf"], "bad.urdf"),
        (["--params-file", "bad.yaml"], "bad.yaml"),
        (["--rated-mass", "0"], "argument --rated-mass: must be > 0, got 0"),
    ],
)
def test_bad_input_is_one_line_a_nonzero_status_and_nothing_written(tmp_path, capsys, monkeypatch, arguments, says):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.urdf").write_text("<robot name='x'><link name='a'/>")
    (tmp_path / "bad.yaml").write_text("/**:\n  ros__parameters:\n    joint_2.link.mass: -3.0\n")
    ur5 = (URDF_DATA / "ur5.urdf").read_text()
    (tmp_path / "huge_effort.urdf").write_text(ur5.replace('effort="150.0"', 'effort="1e300"', 1))
    arguments = [*arguments, "--tip", "tool0"] if "huge_effort.urdf" in arguments else arguments
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow on the way to the refusal
        code = main(["--out", "out", *arguments])
    err = capsys.readouterr().err
    assert code != 0 and err.count("\n") == 1 and says in err and "Traceback" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.urdf", "bad.yaml", "huge_effort.urdf"]


def test_a_step_too_small_is_refused_before_any_work(monkeypatch, capsys):
    """A grid beyond 20,000 points is refused from its size alone: the grid is never made."""
    from irb140_dynamics.tools import load_diagram as tool

    monkeypatch.setattr(tool, "grid", lambda *_: pytest.fail("the grid was made"))
    assert main(["--out", "never", "--step", "1e-9"]) == 2
    assert "--step 1e-09: 300000001 x 200000001 points" in capsys.readouterr().err
    assert tool.grid_size(0.3, 0.01) == 31 and tool.grid_size(0.25, 0.1) == 4 and tool.grid_size(0.0, 0.1) == 1


def test_an_output_that_cannot_be_a_folder_is_refused_before_any_work(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    assert main(["--out", str(tmp_path / "file"), "--step", "0.1"]) == 1
    assert "exists and is not a directory" in capsys.readouterr().err


def test_the_module_runs_as_a_program():
    """(Its console scripts go through the entry like every tool's: test/tools/test_programs.py.)"""
    done = subprocess.run(
        [sys.executable, "-m", "irb140_dynamics.tools.load_diagram", "--help"], capture_output=True, text=True, cwd=ROOT
    )
    assert done.returncode == 0 and done.stdout.startswith("usage: load_diagram") and "--z-max" in done.stdout


def test_every_proven_mass_is_written_rounded_down():
    from irb140_dynamics.core.payload.diagram import DiagramPoint
    from irb140_dynamics.tools.load_diagram_plot import mass_text

    assert mass_text(DiagramPoint(0, 0, 1.23456789, True, 0)) == "1.234567"
    assert mass_text(DiagramPoint(0, 0, math.nan, False, 0)) == ""
    assert mass_text(DiagramPoint(0, 0, math.inf, False, None)) == ""
