"""What the equations tests share: the arms, random states, the generated code loaded."""

from __future__ import annotations

import ctypes
import importlib.util
import shutil
import subprocess

import numpy as np

from irb140_dynamics.core import RigidBody, irb140
from irb140_dynamics.core.urdf import load_urdf

from ...support.paths import URDF_DATA

STATES = 1000
RELATIVE = 1e-9
CC_FLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-O2"]


def arms() -> dict:
    """The arms of the issue: the IRB-140, with 6 kg on the flange, and two URDF arms."""
    return {
        "irb140": irb140(),
        "irb140_6kg": irb140(payload=RigidBody(6.0)),
        "ur5": load_urdf((URDF_DATA / "ur5.urdf").read_text(), tip_link="tool0").model,
        "panda": load_urdf((URDF_DATA / "panda.urdf").read_text(), tip_link="panda_link8").model,
    }


def random_states(n: int, seed: int = 0, count: int = STATES):
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, (count, n)), rng.normal(0.0, 2.0, (count, n)), rng.normal(0.0, 5.0, (count, n))


def assert_close(got, want, what: str):
    """Each state's result within RELATIVE of the largest entry of the reference at that state."""
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape, what
    axes = tuple(range(1, want.ndim))
    scale = np.abs(want).max(axis=axes, keepdims=True)
    error = np.abs(got - want) / scale
    worst = np.unravel_index(np.argmax(error), error.shape)
    assert error.max() <= RELATIVE, f"{what}: relative error {error.max():.3g} at {worst}"


def compiler() -> str | None:
    return shutil.which("cc") or shutil.which("gcc")


def compile_c(folder, prefix: str) -> ctypes.CDLL:
    """The generated .c compiled as the issue asks (warnings are errors) into a shared library."""
    source, library = folder / f"{prefix}_eom.c", folder / f"lib{prefix}.so"
    subprocess.run(
        [compiler(), *CC_FLAGS, "-shared", "-fPIC", str(source), "-o", str(library), "-lm"],
        check=True,
        capture_output=True,
        text=True,
        timeout=120,
    )
    return ctypes.CDLL(str(library))


def import_file(path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def c_function(library, name: str, arguments: int, out_size: int, n_parameters: int = 0):
    """A Python callable (arrays in) -> out array, calling the C function once."""
    fn = getattr(library, name)
    fn.restype = None
    double_p = ctypes.POINTER(ctypes.c_double)

    def call(*arrays, p=None):
        out = np.empty(out_size)
        args = [np.ascontiguousarray(a, dtype=float).ctypes.data_as(double_p) for a in arrays[:arguments]]
        args.append(out.ctypes.data_as(double_p))
        if n_parameters:
            args.append(np.ascontiguousarray(p, dtype=float).ctypes.data_as(double_p))
        fn(*args)
        return out

    return call


def prismatic_arm():
    """The test arm with a prismatic joint, or the reason the core cannot load it."""
    from irb140_dynamics.core.urdf import UrdfError

    try:
        return load_urdf((URDF_DATA / "prismatic_arm.urdf").read_text()).model, None
    except UrdfError as error:
        return None, f"the core does not load a prismatic joint yet ({error})"
