"""Every tool's outputs: all written or none (a destination that cannot take its file leaves
every other destination as it was), never over one of the tool's inputs (refused in one
line naming both, before any work), and with the modes the user's umask gives."""

import os
import shutil
import stat
from pathlib import Path

import numpy as np
import pytest

from irb140_dynamics.core import irb140, rnea_batch
from irb140_dynamics.core.io.atomic import replace_all, write_files
from irb140_dynamics.identification.excitation import optimise_excitation
from irb140_dynamics.tools import (
    calibrate_collision,
    equations,
    excitation,
    export_urdf,
    identify,
    load_diagram,
    record,
    retime,
)
from irb140_dynamics.tools.cli import ToolError
from irb140_dynamics.tools.outputs import Outputs

from ..support.paths import CONFIG, ROOT
from ..support.synthetic_arm import Samples, true_arm, write_csv

URDF = ROOT / "urdf" / "irb140.urdf"
TRAJECTORY = ROOT / "docs" / "trajectory_example.yaml"
ONE_POINT = ["--z-max", "0", "--l-max", "0"]  # load_diagram's smallest grid


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """A 6 s CSV recording of a synthetic IRB-140 along an excitation, with velocities (as
    calibrate_collision's observer needs them)."""
    trajectory = optimise_excitation(irb140(), 3.0, 3, seed=1, iterations=0).trajectory
    t = np.arange(6 * 200) / 200.0
    Q, QD, QDD = trajectory.evaluate(t)
    tau = rnea_batch(true_arm(1), Q, QD, QDD)
    return write_csv(
        tmp_path_factory.mktemp("recording") / "run.csv",
        Samples(t, Q, QD, tau, tau),
        irb140().joint_names,
        with_velocity=True,
    )


def left_in(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


# all or none


def test_a_commit_that_fails_on_its_second_file_leaves_the_first_as_it_was(tmp_path):
    """A folder appears where the second output goes while the tool works: the first keeps
    its old bytes, nothing else is left behind, the error names the second as typed."""
    (tmp_path / "a.csv").write_text("old")
    refused = pytest.raises(ToolError, match=r"^out/b\.png: cannot write \(Is a directory\); nothing written$")
    with refused, Outputs() as outputs:
        outputs.text(tmp_path / "a.csv", "out/a.csv", "new")
        outputs.text(tmp_path / "b.png", "out/b.png", "new")
        (tmp_path / "b.png").mkdir()
        outputs.commit()
    assert (tmp_path / "a.csv").read_text() == "old"
    assert left_in(tmp_path) == ["a.csv", "b.png"]


def test_a_rename_that_fails_half_way_puts_back_every_file_replaced_before_it(tmp_path):
    """The second rename fails after the first replaced its target (its temporary gone):
    the first target has its old file again, the one that did not exist is not made."""
    for name, text in (("x", "old x"), ("y", "old y")):
        (tmp_path / name).write_text(text)
    new = {name: tmp_path / f".new-{name}" for name in ("x", "y", "z")}
    for name, path in new.items():
        path.write_text(f"new {name}")
    new["y"].unlink()
    with pytest.raises(FileNotFoundError) as error:
        replace_all([(new["x"], tmp_path / "x"), (new["z"], tmp_path / "z"), (new["y"], tmp_path / "y")])
    assert error.value.filename == str(tmp_path / "y")
    assert (tmp_path / "x").read_text() == "old x" and (tmp_path / "y").read_text() == "old y"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x", "y"]  # no z, nothing kept aside
    write_files({tmp_path / "x": b"1", tmp_path / "y": b"2"})  # and when all can be renamed, all are
    assert (tmp_path / "x").read_text() == "1" and (tmp_path / "y").read_text() == "2"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x", "y"]


def test_load_diagram_with_a_folder_where_its_png_goes_keeps_its_old_csv(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "o"
    out.mkdir()
    (out / "load_diagram.csv").write_text("old")
    (out / "load_diagram.png").mkdir()
    assert load_diagram.main(["--out", "o", *ONE_POINT]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err == ["load_diagram: error: o/load_diagram.png: is a directory"], err
    assert (out / "load_diagram.csv").read_text() == "old" and left_in(out) == ["load_diagram.csv", "load_diagram.png"]


def test_identify_with_a_folder_where_a_plot_goes_keeps_the_other_plot_and_writes_nothing(
    recording, tmp_path, capsys, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    plots = tmp_path / "plots"
    plots.mkdir()
    (plots / "torques.png").write_text("old")
    (plots / "residuals.png").mkdir()
    assert identify.main([str(recording), "--out", "identified.yaml", "--plots", "plots/", "--quiet"]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err == ["identify: error: plots/residuals.png: is a directory"], err
    assert (plots / "torques.png").read_text() == "old" and left_in(tmp_path) == [
        "plots",
        "plots/residuals.png",
        "plots/torques.png",
    ]


# no output over an input


def _copy(source, target):
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(source, target)
    return target


CASES = {
    # tool: (its main, the files it reads (made in tmp_path), its arguments, the input's and output's as shown)
    "load_diagram --urdf": (
        load_diagram.main,
        {"o/load_diagram.csv": URDF},
        ["--urdf", "o/load_diagram.csv", "--out", "o", *ONE_POINT],
        ("--urdf o/load_diagram.csv", "o/load_diagram.csv"),
    ),
    "load_diagram --params-file": (
        load_diagram.main,
        {"o/load_diagram.png": CONFIG},
        ["--params-file", "o/load_diagram.png", "--out", "o/", *ONE_POINT],
        ("--params-file o/load_diagram.png", "o/load_diagram.png"),
    ),
    "excitation": (
        excitation.main,
        {"arm.yaml": CONFIG},
        ["--params-file", "arm.yaml", "--out", "./arm.yaml", "--iterations", "0"],
        ("--params-file arm.yaml", "./arm.yaml"),
    ),
    "identify --urdf-out": (
        identify.main,
        {"run.csv": None, "arm.urdf": URDF},
        ["run.csv", "--urdf", "arm.urdf", "--out", "identified.yaml", "--urdf-out", "arm.urdf"],
        ("--urdf arm.urdf", "arm.urdf"),
    ),
    "identify the URDF beside --out": (
        identify.main,
        {"run.csv": None, "arm.urdf": URDF},
        ["run.csv", "--urdf", "arm.urdf", "--out", "arm.yaml"],
        ("--urdf arm.urdf", "arm.urdf"),
    ),
    "identify --plots": (
        identify.main,
        {"run.csv": None, "plots/torques.png": CONFIG},
        ["run.csv", "--params-file", "plots/torques.png", "--out", "identified.yaml", "--plots", "plots"],
        ("--params-file plots/torques.png", "plots/torques.png"),
    ),
    "identify into its bag": (
        identify.main,
        {"bag/metadata.yaml": CONFIG},
        ["bag", "--out", "bag/identified.yaml"],
        ("bag", "bag/identified.yaml"),
    ),
    "equations": (
        equations.main,
        {"gen/arm_eom.py": CONFIG},
        ["--params-file", "gen/arm_eom.py", "--form", "python", "--prefix", "arm", "--out", "gen"],
        ("--params-file gen/arm_eom.py", "gen/arm_eom.py"),
    ),
    "export_urdf": (
        export_urdf.main,
        {"arm.urdf": URDF},
        ["export_urdf", "--urdf", "arm.urdf", "--out", "arm.urdf"],
        ("--urdf arm.urdf", "arm.urdf"),
    ),
    "retime OUT": (
        retime.main,
        {"arm.yaml": CONFIG, "in.yaml": TRAJECTORY},
        ["--params-file", "arm.yaml", "in.yaml", "in.yaml"],
        ("in.yaml", "in.yaml"),
    ),
    "retime --plot": (
        retime.main,
        {"arm.yaml": CONFIG, "in.yaml": TRAJECTORY},
        ["--params-file", "arm.yaml", "--check-only", "in.yaml", "--plot", "arm.yaml"],
        ("--params-file arm.yaml", "arm.yaml"),
    ),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_no_tool_writes_over_one_of_its_inputs(case, recording, tmp_path, capsys, monkeypatch):
    main, files, arguments, (given, written) = CASES[case]
    monkeypatch.chdir(tmp_path)
    for name, source in files.items():
        _copy(source or recording, tmp_path / name)
    before = {name: (tmp_path / name).read_bytes() for name in files}
    capsys.readouterr()
    assert main(arguments) == 1
    err = capsys.readouterr().err.splitlines()
    tool = main.__module__.rsplit(".", 1)[1]
    why = (
        "write into the input {}; give the output another place"
        if "into" in case
        else "replace the input {}; give the output another name"
    )
    assert err == [f"{tool}: error: {written}: would {why.format(given)}"], err
    assert {name: (tmp_path / name).read_bytes() for name in files} == before
    folders = {os.path.dirname(name) for name in files} - {""}
    assert left_in(tmp_path) == sorted({*files, *folders})


@pytest.mark.ros  # the node's parameters, or record's ROS side: rclpy
def test_record_refuses_an_existing_input_as_its_bag(tmp_path, capsys, monkeypatch):
    """record's bag must be new: an existing file (its parameter file here) is refused."""
    monkeypatch.chdir(tmp_path)
    _copy(CONFIG, tmp_path / "arm.yaml")
    assert record.main(["record", "--out", "arm.yaml", "--ros-args", "--params-file", "arm.yaml"]) == 1
    assert capsys.readouterr().err.splitlines() == ["record: error: arm.yaml: exists already; give a new name"]
    assert (tmp_path / "arm.yaml").read_bytes() == CONFIG.read_bytes()


# modes


@pytest.fixture(params=[0o022, 0o027])
def umask(request):
    previous = os.umask(request.param)
    yield request.param
    os.umask(previous)


def modes(folder, mask) -> dict:
    """Each file (and folder) written under ``folder`` whose mode is not the umask's."""
    wrong = {}
    for path in folder.rglob("*"):
        expected = (0o777 if path.is_dir() else 0o666) & ~mask
        if stat.S_IMODE(path.stat().st_mode) != expected:
            wrong[str(path.relative_to(folder))] = oct(stat.S_IMODE(path.stat().st_mode))
    return wrong


RUNS = {
    "calibrate_collision": (calibrate_collision.main, ["RECORDING", "--out", "o/collision.yaml", "--quiet"], 1),
    "load_diagram": (load_diagram.main, ["--out", "o/diagram", *ONE_POINT], 2),
    "excitation": (
        excitation.main,
        ["--out", "o/excitation.yaml", "--iterations", "0", "--period", "2", "--harmonics", "2", "--rate", "5"],
        1,
    ),
    "export_urdf": (export_urdf.main, ["export_urdf", "--out", "o/arm.urdf"], 1),
    "equations": (
        equations.main,
        ["--params-file", CONFIG, "--form", "c", "--what", "g", "--out", "o/gen"],
        2,
    ),
    "retime": (retime.main, ["--params-file", CONFIG, TRAJECTORY, "o/out.yaml", "--plot", "o/out.png"], 2),
    "identify": (
        identify.main,
        ["RECORDING", "--urdf", URDF, "--out", "o/arm.yaml", "--plots", "o/plots/", "--quiet"],
        4,
    ),
}
# What a run says it wrote: identify names its plots as typed, in one path (--plots o/plots/,
# the folder with its slash: 'wrote o/plots/torques.png', no '//').
WROTE = {
    "identify": ["wrote o/arm.yaml", "wrote o/arm.urdf", "wrote o/plots/torques.png", "wrote o/plots/residuals.png"]
}


@pytest.mark.slow  # identify and the retiming's kernels
@pytest.mark.parametrize("tool", sorted(RUNS))
def test_every_file_a_tool_writes_has_the_mode_the_umask_gives(tool, umask, recording, tmp_path, monkeypatch, capsys):
    """Each file written has the umask's mode; and the run says it wrote what WROTE has
    (one identification for both checks)."""
    main, arguments, count = RUNS[tool]
    monkeypatch.chdir(tmp_path)
    (tmp_path / "o").mkdir()
    arguments = [str(recording) if a == "RECORDING" else str(a) for a in arguments]
    assert main(arguments) == 0, capsys.readouterr().err
    if tool in WROTE:
        wrote = [line for line in capsys.readouterr().out.splitlines() if line.startswith("wrote ")]
        assert wrote == WROTE[tool], wrote
    files = [p for p in (tmp_path / "o").rglob("*") if p.is_file()]
    assert len(files) == count, files
    assert modes(tmp_path / "o", umask) == {}


def test_a_file_in_a_missing_folder_is_named_as_asked_not_by_its_temporary(tmp_path):
    target = tmp_path / "missing" / "out.yaml"
    with pytest.raises(OSError) as raised:
        write_files({target: b"x"})
    assert raised.value.filename == str(target)
    assert not (tmp_path / "missing").exists()


def test_retime_names_the_output_asked_for_when_its_folder_is_missing(tmp_path, capsys):
    example = Path(__file__).parents[2] / "docs" / "trajectory_example.yaml"
    assert retime.main([str(example), str(tmp_path / "missing" / "out.yaml")]) == 1
    err = capsys.readouterr().err.strip()
    assert f"{tmp_path / 'missing' / 'out.yaml'}: cannot write" in err and ".irb140-" not in err, err
