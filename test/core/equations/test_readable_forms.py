"""The SymPy and LaTeX forms: the SymPy module rebuilds expressions equal to the core; the
LaTeX document's trigonometric series equal the core, combine products into sums of angles,
and the document compiles with pdflatex (where it is installed)."""

import shutil
import subprocess

import numpy as np
import pytest
import sympy as sp

from irb140_dynamics.core import coriolis_batch, gravity_batch, mass_matrix, mass_matrix_batch, rnea_batch
from irb140_dynamics.core.equations import generate, latex
from irb140_dynamics.core.equations import trig_products as tp

from .support import arms, assert_close, import_file, random_states

ARMS = arms()


@pytest.mark.slow
def test_sympy_module_rebuilds_the_expressions(tmp_path):
    model = ARMS["irb140_6kg"]
    files = generate(model, ("sympy",), prefix="irb140")
    (tmp_path / "irb140_eom_sympy.py").write_text(files["irb140_eom_sympy.py"])
    module = import_file(tmp_path / "irb140_eom_sympy.py", "generated_sympy")
    assert [s.name for s in module.q] == [f"q{i}" for i in range(1, 7)]
    assert module.M.shape == (6, 6) and module.tau.shape == (6, 1)
    Q, QD, QDD = random_states(6, seed=5, count=20)
    arguments = [*module.q, *module.qd, *module.qdd]
    functions = {
        name: sp.lambdify(arguments, getattr(module, name), "numpy", cse=True) for name in ("tau", "M", "Cqd", "g")
    }
    got = {
        name: np.array([np.asarray(fn(*q, *qd, *qdd), dtype=float) for q, qd, qdd in zip(Q, QD, QDD)])
        for name, fn in functions.items()
    }
    assert_close(got["tau"][..., 0], rnea_batch(model, Q, QD, QDD), "tau (SymPy)")
    assert_close(got["M"], mass_matrix_batch(model, Q), "M (SymPy)")
    assert_close(got["Cqd"][..., 0], coriolis_batch(model, Q, QD), "Cqd (SymPy)")
    assert_close(got["g"][..., 0], gravity_batch(model, Q), "g (SymPy)")
    # built on: entries are expressions of the symbols
    assert module.M[1, 2] == module.M[2, 1]


@pytest.mark.parametrize("arm", ["irb140_6kg", "ur5"])
def test_the_written_forms_equal_the_core(arm):
    """The polynomials in sines and cosines the LaTeX prints (before rounding) are the core's."""
    model = ARMS[arm]
    series = latex.series(model, {"M", "Cqd", "g"})
    assert set(series) == {"M", "Cqd", "g"}, "the series are short enough for these arms"
    runs = tp.angle_runs(list(series.values()), model.n)
    Q, QD, _ = random_states(model.n, seed=6, count=50)

    products = {name: [tp.products(x, runs, 0.0) for x in entries] for name, entries in series.items()}

    def values(name, q, qd=()):
        return [tp.value(x, runs, q, qd) for x in products[name]]

    assert_close(np.array([values("g", q) for q in Q]), gravity_batch(model, Q), "g written")
    M = np.array([values("M", q) for q in Q]).reshape(-1, model.n, model.n)
    assert_close(M, mass_matrix_batch(model, Q), "M written")
    assert_close(np.array([values("Cqd", q, qd) for q, qd in zip(Q, QD)]), coriolis_batch(model, Q, QD), "Cqd written")


def test_parallel_joints_angles_are_summed():
    """The IRB-140's joints 2 and 3 turn about parallel axes: its g_2 is written with
    c23 = cos(q2 + q3), no product c2 c3; the UR5's joints 2, 3, 4 likewise."""
    tex = generate(ARMS["irb140"], ("latex",), what=("g",), prefix="irb140")["irb140_eom.tex"]
    g2 = next(line for line in tex.splitlines() if line.startswith("g_{2} &="))
    assert "c_{23}" in g2 and "s_{2}" in g2, g2
    assert "c_{2} c_{3}" not in tex and r"$c_{23} = \cos(q_{2} + q_{3})$" in tex
    series = latex.series(ARMS["ur5"], {"g"})
    assert [len(joints) for joints in tp.angle_sums(tp.angle_runs(list(series.values()), 6))] == [1, 1, 2, 3, 1, 1]


def test_constant_entries_are_written():
    """The IRB-140's M_66 (joint 6 turns only its own link: a constant) is the core's."""
    model = ARMS["irb140"]
    tex = generate(model, ("latex",), what=("M",), prefix="irb140")["irb140_eom.tex"]
    m66 = next(line for line in tex.splitlines() if line.startswith("M_{66} &="))
    assert m66.split("=")[1].split()[0] == f"{mass_matrix(model, [0.3] * 6)[5, 5]:.6g}", m66


@pytest.mark.slow
def test_the_document_compiles(tmp_path):
    if shutil.which("pdflatex") is None:
        pytest.skip("pdflatex is not installed (texlive-latex-base): the .tex is not compiled")
    for arm, symbolic in (("irb140", False), ("ur5", True)):
        files = generate(ARMS[arm], ("latex",), symbolic=symbolic, prefix=arm)
        (tmp_path / f"{arm}_eom.tex").write_text(files[f"{arm}_eom.tex"])
        result = subprocess.run(
            ["pdflatex", "-interaction=nonstopmode", "-halt-on-error", f"{arm}_eom.tex"],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=240,
        )
        assert result.returncode == 0, result.stdout[-2000:]
        assert (tmp_path / f"{arm}_eom.pdf").stat().st_size > 0
