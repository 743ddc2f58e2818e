"""bench/bench_cpp.py's pieces, without the benchmark: it says what is missing when it
cannot build, the arm's C it times compiles into the library its driver loads (the same
numbers as the package), and the arm file its driver reads has one line per joint."""

import ctypes
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from irb140_dynamics.core import rnea
from test.support.common import random_urdf_model

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
import bench_cpp  # noqa: E402  (bench/ is not a package)


def _prefix(tmp_path: Path, files: list[str]) -> Path:
    prefix = tmp_path / "cmeel.prefix"
    for file in files:
        (prefix / file).parent.mkdir(parents=True, exist_ok=True)
        (prefix / file).write_text("")
    return prefix


PINOCCHIO = ["include/pinocchio/codegen/cppadcg-algo.hpp", "lib/libpinocchio_default.so"]


def test_without_the_cppad_wheels_it_names_them(tmp_path, monkeypatch):
    prefix = _prefix(tmp_path, [*PINOCCHIO, "include/eigen3/Eigen/Dense"])
    monkeypatch.setattr(bench_cpp, "prefix_dirs", lambda: [prefix])
    monkeypatch.setattr(shutil, "which", lambda name: f"/usr/bin/{name}")
    settings, why = bench_cpp.build_settings()
    assert settings is None
    assert why == "no cmeel-cppad and no cmeel-cppadcodegen headers: pip install -r requirements/bench.txt"
    _prefix(tmp_path, ["include/cppad/cppad.hpp"])
    assert bench_cpp.build_settings()[1] == "no cmeel-cppadcodegen headers: pip install -r requirements/bench.txt"
    _prefix(tmp_path, ["include/cppad/cg.hpp"])
    settings, why = bench_cpp.build_settings()
    assert why is None
    assert settings["includes"] == [prefix / "include", prefix / "include/eigen3"]


def test_without_pinocchio_codegen_or_a_compiler_it_says_so(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(bench_cpp, "prefix_dirs", lambda: [_prefix(tmp_path, ["include/pinocchio/algorithm/rnea.hpp"])])
    monkeypatch.setattr(shutil, "which", lambda name: f"/usr/bin/{name}")
    assert "cppadcg-algo.hpp" in bench_cpp.build_settings()[1]
    monkeypatch.setattr(shutil, "which", lambda name: None)
    assert bench_cpp.build_settings() == (None, "no C and C++ compiler (gcc and g++) on PATH")
    monkeypatch.setattr(sys, "argv", ["bench_cpp.py"])
    bench_cpp.main()  # one line, nothing measured, no exception
    assert capsys.readouterr().out == (
        "bench_cpp: cannot build the C++ benchmark: no C and C++ compiler (gcc and g++) on PATH; nothing measured\n"
    )


@pytest.mark.skipif(shutil.which("gcc") is None, reason="no gcc")
def test_the_arm_library_is_the_package_s_numbers(tmp_path):
    model = random_urdf_model(np.random.default_rng(3), 2)
    settings = {"gcc": shutil.which("gcc")}
    library = ctypes.CDLL(str(bench_cpp.arm_library(model, tmp_path, settings, what=("tau",))))
    q, qd, qdd = np.array([0.3, -1.2]), np.array([0.5, 2.0]), np.array([-1.0, 4.0])
    tau = np.zeros(2)
    pointer = ctypes.POINTER(ctypes.c_double)
    library.arm_tau(*(x.ctypes.data_as(pointer) for x in (q, qd, qdd, tau)))
    np.testing.assert_allclose(tau, rnea(model, q, qd, qdd), rtol=1e-12, atol=1e-12)


def test_the_arm_file_has_a_line_per_joint():
    model = bench_cpp.random_chain(3, 1)
    gravity, *joints = bench_cpp.model_text(model).splitlines()
    assert gravity.split()[0] == "gravity" and len(gravity.split()) == 4
    assert [line.split()[:2] for line in joints] == [["0", "RU"], ["1", "RU"], ["2", "RU"]]
    assert all(len(line.split()) == 31 for line in joints)
