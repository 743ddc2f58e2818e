"""The equations command: its files, bad input refused in one line with nothing written,
the progress line, and the same bytes from the same input."""

import os
import subprocess
import sys

import numpy as np
import pytest

from irb140_dynamics.tools import equations as tool

from ..core.equations.support import import_file
from ..support.paths import CONFIG, ROOT, URDF_DATA

STRETCHED = [0.0, -np.pi / 2, np.pi / 2, 0.0, 0.0, 0.0]


def run(capsys, *args):
    status = tool.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def test_writes_its_files_and_leaves_the_rest(tmp_path, capsys):
    out = tmp_path / "gen"
    out.mkdir()
    (out / "mine.txt").write_text("not the tool's")
    (out / "irb140_eom.py").write_text("an older version")
    status, printed, err = run(
        capsys, "--params-file", CONFIG, "--form", "python", "--what", "g", "--payload-mass", "6", "--out", out
    )
    assert status == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["irb140_eom.py", "mine.txt"]  # no temp folder left
    assert (out / "mine.txt").read_text() == "not the tool's"
    assert printed.split() == [str(out / "irb140_eom.py")]
    g = import_file(out / "irb140_eom.py", "tool_irb140").g(STRETCHED)
    # the report's torques with 6 kg at the flange, as printed
    assert np.allclose(g[[1, 2, 4]], [290.765, 105.348, 6.25594], rtol=0, atol=[5e-4, 5e-4, 5e-6])


def test_urdf_chain_and_prefix(tmp_path, capsys):
    status, _, err = run(
        capsys,
        "--urdf",
        URDF_DATA / "ur5.urdf",
        "--tip",
        "tool0",
        "--form",
        "c",
        "--what",
        "g",
        "--prefix",
        "ur",
        "--out",
        tmp_path,
    )
    assert status == 0, err
    header = (tmp_path / "ur_eom.h").read_text()
    assert "void ur_g(const double q[6], double g[6]);" in header
    assert "shoulder_pan_joint" in header


@pytest.mark.parametrize(
    "args, reason",
    [
        (["--params-file", "missing.yaml", "--form", "c"], "no such file"),
        (["--params-file", "{bad}", "--form", "c"], "bad.yaml"),
        (["--urdf", "{bad}", "--form", "c"], "bad.yaml"),
        (["--urdf", URDF_DATA / "ur5.urdf", "--tip", "nowhere", "--form", "c"], "nowhere"),
        (["--params-file", CONFIG, "--form", "fortran"], "unknown form 'fortran'"),
        (["--params-file", CONFIG, "--form", "c", "--what", "tau,D"], "unknown quantity 'D'"),
        (["--params-file", CONFIG, "--form", "c", "--prefix", "2fast"], "not a C identifier"),
        (["--params-file", CONFIG, "--form", "c", "--payload-mass", "-1"], "payload"),
        (["--params-file", CONFIG, "--form", "c", "--base", "world"], "--base and --tip choose a URDF's chain"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, args, reason):
    bad = tmp_path / "bad.yaml"
    bad.write_text("joint_names: [a\n")
    out = tmp_path / "out"
    args = [str(bad) if a == "{bad}" else a for a in args]
    status, printed, err = run(capsys, *args, "--out", out)
    assert status != 0
    assert reason in err and err.count("\n") == 1 and "Traceback" not in err, err
    assert printed == ""
    assert not out.exists()


@pytest.mark.parametrize(
    "args",
    [
        ["--urdf", "{two_arms}", "--form", "sympy", "--what", "regressor", "--symbolic-parameters"],
        ["--params-file", CONFIG, "--form", "latex", "--what", "dtau"],
    ],
    ids=["symbolic parameters with mimic joints", "dtau not in C"],
)
def test_a_refused_generation_leaves_no_out_folder(tmp_path, capsys, args):
    from ..support.two_arms import TWO_ARMS

    (tmp_path / "two_arms.urdf").write_text(TWO_ARMS)
    args = [str(tmp_path / "two_arms.urdf") if a == "{two_arms}" else a for a in args]
    status, printed, err = run(capsys, *args, "--out", tmp_path / "new" / "out")
    assert status == 1 and printed == "" and err.count("\n") == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["two_arms.urdf"]  # no out, nor its parent


def test_unwritable_out_is_one_line(tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    status, _, err = run(capsys, "--params-file", CONFIG, "--form", "c", "--out", blocker / "gen")
    assert status != 0 and err.count("\n") == 1 and "a_file is not a directory" in err, err


def test_a_failure_while_generating_writes_nothing(tmp_path, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise ValueError("generation failed")

    monkeypatch.setattr(tool, "generate", broken)
    out = tmp_path / "out"
    out.mkdir()
    status, _, err = run(capsys, "--params-file", CONFIG, "--form", "c", "--out", out)
    assert status != 0 and "generation failed" in err
    assert list(out.iterdir()) == []


def test_progress_line_after_the_quiet_time(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(tool, "QUIET_SECONDS", 0.0)
    status, _, err = run(capsys, "--params-file", CONFIG, "--form", "python", "--what", "M", "--out", tmp_path)
    assert status == 0
    lines = err.splitlines()
    assert lines[-1].startswith("equations: done in ") and lines[-1].endswith(" s"), err
    assert "equations: writing the python form (" in err, err


@pytest.mark.slow
@pytest.mark.process
def test_same_input_same_bytes(tmp_path):
    """Two runs as processes, with different hash seeds: the same files, byte for byte. Each
    process writes both forms (the C of tau, M, C, g; the LaTeX of M, g) through the tool's
    main, one after the other; the two seeds' processes go side by side (one per core)."""

    def start(seed: str):
        env = {**os.environ, "PYTHONHASHSEED": seed, "PYTHONPATH": str(ROOT)}
        runs = [
            ["--params-file", str(CONFIG), "--form", form, "--what", what, "--out", str(tmp_path / seed)]
            for form, what in (("c", "tau,M,C,g"), ("latex", "M,g"))
        ]
        script = (
            "import sys\nfrom irb140_dynamics.tools import equations\n"
            f"sys.exit(max(equations.main(arguments) for arguments in {runs!r}))"
        )
        return subprocess.Popen(
            [sys.executable, "-c", script], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
        )

    processes = [start(seed) for seed in ("1", "2")]
    for process in processes:
        _, err = process.communicate(timeout=300)
        assert process.returncode == 0, err
    outputs = [{p.name: p.read_bytes() for p in sorted((tmp_path / seed).iterdir())} for seed in ("1", "2")]
    assert outputs[0] and outputs[0] == outputs[1]
    assert sorted(outputs[0]) == ["irb140_eom.c", "irb140_eom.h", "irb140_eom.tex"]
