"""The tools on a whole tree (Baxter, test/data/urdf; test_urdf_trees' TWO_ARMS): the payload
analysis (load_diagram, excitation --payload, identify --payload-only) refused in one line
naming --tip, nothing written; export_urdf writes the tree and its mimic joints (read back:
the same dynamics); equations writes the tree's code (the same torques as the core's) and the
regressor of mimic joints (the core's)."""

import numpy as np
import pytest

from irb140_dynamics.core import gravity, mass_matrix, rnea
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.regressor import regressor_batch
from irb140_dynamics.tools import equations, excitation, export_urdf, identify, load_diagram

from ..core.equations.support import import_file
from ..core.equations.test_mimic_regressor import GRIPPER
from ..core.test_urdf_trees import TWO_ARMS
from ..support.paths import URDF_DATA

BAXTER = URDF_DATA / "baxter.urdf"


def run(capsys, tool, *args):  # export_urdf.main takes sys.argv, its name first
    status = tool.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.parametrize(
    "tool, args, what",
    [
        (load_diagram, ["--out", "{out}/diagram.png"], "load_diagram"),
        (excitation, ["--payload", "--out", "{out}/excitation.yaml"], "excitation --payload"),
        (identify, ["--payload-only", "{out}/bag", "--out", "{out}/payload.yaml"], "identify --payload-only"),
    ],
)
def test_the_payload_analysis_on_a_tree_is_refused_naming_tip(tool, args, what, tmp_path, capsys):
    (tmp_path / "bag").mkdir()  # a recording's folder (identify reads none before the model)
    status, out, err = run(capsys, tool, "--urdf", BAXTER, *(a.format(out=tmp_path) for a in args))
    lines = err.strip().splitlines()
    assert status == 1 and len(lines) == 1 and not out, err
    assert f"{what} takes one serial chain" in lines[0] and "--tip" in lines[0] and "tree" in lines[0]
    assert [p.name for p in tmp_path.iterdir()] == ["bag"] and not list((tmp_path / "bag").iterdir())


def test_export_urdf_writes_the_tree_and_its_mimic_joints(tmp_path, capsys):
    status, _, err = run(capsys, export_urdf, "export_urdf", "--urdf", BAXTER, "--out", tmp_path / "baxter.urdf")
    assert status == 0, err
    model = load_urdf(BAXTER.read_text()).model
    back = load_urdf((tmp_path / "baxter.urdf").read_text()).model
    assert (back.joint_names, back.parent, back.mimics) == (model.joint_names, model.parent, model.mimics)
    rng = np.random.default_rng(4)
    for _ in range(3):
        q, qd, qdd = (rng.uniform(-1.0, 1.0, model.n) for _ in range(3))
        np.testing.assert_allclose(rnea(back, q, qd, qdd), rnea(model, q, qd, qdd), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(mass_matrix(back, q), mass_matrix(model, q), rtol=1e-12, atol=1e-12)


def test_equations_of_a_tree_with_mimic_joints_are_the_cores(tmp_path, capsys):
    urdf = tmp_path / "two_arms.urdf"
    urdf.write_text(TWO_ARMS)
    status, printed, err = run(capsys, equations, "--urdf", urdf, "--form", "python", "--out", tmp_path / "gen")
    assert status == 0, err
    code = import_file(printed.split()[0], "two_arms_eom")
    model = load_urdf(TWO_ARMS).model
    rng = np.random.default_rng(8)
    q, qd, qdd = (rng.uniform(-1.0, 1.0, model.n) for _ in range(3))
    np.testing.assert_allclose(code.tau(q, qd, qdd), rnea(model, q, qd, qdd), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(code.M(q), mass_matrix(model, q), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(code.g(q), gravity(model, q), rtol=1e-12, atol=1e-12)
    status, _, err = run(
        capsys, equations, "--urdf", urdf, "--form", "latex", "--symbolic-parameters", "--out", tmp_path / "sym"
    )
    assert status == 1 and len(err.strip().splitlines()) == 1 and "mimic joints" in err


def test_equations_write_the_regressor_of_mimic_joints_as_the_core(tmp_path, capsys):
    """The Python form (C, SymPy, LaTeX: test/core/equations/test_mimic_regressor.py)."""
    urdf = tmp_path / "gripper.urdf"
    urdf.write_text(GRIPPER)
    out = tmp_path / "gen"
    status, _, err = run(capsys, equations, "--urdf", urdf, "--what", "regressor", "--form", "python", "--out", out)
    assert status == 0, err
    code = import_file(out / "gripper_eom.py", "gripper_regressor_eom")
    model = load_urdf(GRIPPER).model
    rng = np.random.default_rng(41)
    Q, QD, QDD = (rng.uniform(-1.0, 1.0, (3, model.n)) for _ in range(3))
    want = regressor_batch(model, Q, QD, QDD)
    np.testing.assert_allclose(code.regressor(Q, QD, QDD), want, rtol=1e-12, atol=1e-12)
    assert code.REGRESSOR_COLUMNS[-3:] == ("viscous3", "coulomb3", "armature3")
