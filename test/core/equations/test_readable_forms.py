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
from irb140_dynamics.core.equations import trig_series as ts

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
def test_the_series_equal_the_core(arm):
    model = ARMS[arm]
    series = latex.series(model, {"M", "Cqd", "g"})
    assert set(series) == {"M", "Cqd", "g"}, "the series are short enough for these arms"
    Q, QD, _ = random_states(model.n, seed=6, count=50)

    def values(entries, q, qd):
        return np.array([x.value(q, qd) if isinstance(x, ts.Series) else x for x in entries])

    assert_close(np.array([values(series["g"], q, ()) for q in Q]), gravity_batch(model, Q), "g series")
    M = np.array([values(series["M"], q, ()) for q in Q]).reshape(-1, model.n, model.n)
    assert_close(M, mass_matrix_batch(model, Q), "M series")
    assert_close(
        np.array([values(series["Cqd"], q, qd) for q, qd in zip(Q, QD)]), coriolis_batch(model, Q, QD), "Cqd series"
    )


def test_products_of_angles_become_sums():
    """The IRB-140's joints 2 and 3 turn about parallel axes: g_2 holds cos(q2 + q3), no c2 c3."""
    files = generate(ARMS["irb140"], ("latex",), what=("g",), prefix="irb140")
    tex = files["irb140_eom.tex"]
    g2 = next(line for line in tex.splitlines() if line.startswith("g_{2} &="))
    assert r"\cos(q_{2} + q_{3})" in g2 and r"\sin(q_{2})" in g2, g2
    assert r"\cos(q_{2}) \cos(q_{3})" not in tex


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
