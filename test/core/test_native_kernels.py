"""Native kernels (the native room: irb140_dynamics.native): the C form of a kernel gives the Python form's
numbers bit for bit, refuses what the Python form refuses, and is only ever an
acceleration: without a compiler, with IRB140_NATIVE=0, or when compiling fails, the
Python form answers. The session's cache is its own (test/conftest.py)."""

import contextlib
import os
import shutil
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from irb140_dynamics import native, native_hook
from irb140_dynamics.core import Friction, RigidBody, RobotModel, gravity, irb140, mass_matrix, prepare, rnea
from irb140_dynamics.core.codegen import c_code
from irb140_dynamics.core.codegen.kernels import NATIVE_KERNELS, PROMOTE_AFTER, kernels_of
from irb140_dynamics.core.codegen.recipes import WITH_FRICTION
from irb140_dynamics.core.urdf import load_urdf
from irb140_dynamics.native import compiler, library

from ..support.common import OFFSET_PAYLOAD
from ..support.paths import URDF_DATA
from .test_urdf_trees import TWO_ARMS

pytestmark = pytest.mark.skipif(native.c_compiler() is None, reason="no C compiler on this machine")

KERNELS = ("rnea", "gravity_torques", "mass_matrix")


@pytest.fixture(autouse=True)
def compiles_at_normal_priority(monkeypatch):
    """These tests wait for their compiles: at the lowest priority, on two cores kept busy,
    each would take minutes (the priority is for a node's loop, not a test's wait)."""
    monkeypatch.setattr(library, "NICENESS", 0)


def arms() -> dict:
    def urdf(name, **chain):
        return load_urdf((URDF_DATA / name).read_text(), **chain).model

    return {
        "irb140 with an offset payload": lambda: irb140(payload=OFFSET_PAYLOAD),
        "ur5": lambda: urdf("ur5.urdf", tip_link="tool0"),
        "panda": lambda: urdf("panda.urdf", tip_link="panda_link8"),
        "prismatic arm": lambda: urdf("prismatic_arm.urdf"),
        "panda tree, a mimic finger": lambda: urdf("panda.urdf"),
        "two arms, mimic joints before their joint": lambda: load_urdf(TWO_ARMS).model,
        "no payload or gravity constants": no_constants,
    }


def no_constants():
    """The IRB-140 with massless links and no payload in zero gravity: its kernels' ``k`` is
    empty (a link's inertia is an input of k where the payload's regrouping reaches it)."""
    model = irb140().with_gravity((0.0, 0.0, 0.0))
    model = replace(model, joints=tuple(replace(joint, link=RigidBody()) for joint in model.joints))
    assert kernels_of(model).constants == ()
    return model


def frictionless(model):
    return replace(model, joints=tuple(replace(j, friction=Friction()) for j in model.joints))


def offset_arm():
    """The IRB-140 with an offset payload, no friction: the arm most tests here compile (the
    bit-for-bit test's first), so that its kernels are compiled once in a run."""
    return frictionless(irb140(payload=OFFSET_PAYLOAD))


def promoted(model, names=KERNELS):
    """The model with its kernels compiled as C (asked for at once, not after PROMOTE_AFTER calls)."""
    done = prepare(model, timeout=120.0, names=names)
    assert done.native and kernels_of(model).is_native(*names), done
    return model


def python_calls(monkeypatch, kernels) -> list:
    """The calls of these kernels' Python forms from now on (each counted by ``used``)."""
    calls = []
    for kernel in kernels:
        monkeypatch.setattr(kernel, "used", lambda kernel=kernel: calls.append(kernel))
    return calls


def states(model, count=200, seed=5):
    rng = np.random.default_rng(seed)
    shape = (count, model.n)
    return rng.uniform(-3.0, 3.0, shape), rng.uniform(-3.0, 3.0, shape), rng.uniform(-10.0, 10.0, shape)


@pytest.mark.parametrize("arm", sorted(arms()))
def test_native_kernels_give_the_python_numbers_bit_for_bit(arm):
    python_model, native_model = (frictionless(arms()[arm]()) for _ in range(2))
    promoted(native_model)
    for q, qd, qdd in zip(*states(native_model)):
        np.testing.assert_array_equal(rnea(native_model, q, qd, qdd), rnea(python_model, q, qd, qdd))
        np.testing.assert_array_equal(gravity(native_model, q), gravity(python_model, q))
        np.testing.assert_array_equal(mass_matrix(native_model, q), mass_matrix(python_model, q))
    assert kernels_of(python_model).rnea.native is None  # compared with the Python form indeed


def test_a_kernel_is_compiled_after_enough_calls_and_used_from_then_on(monkeypatch):
    model = offset_arm()
    q = np.linspace(-1.0, 1.0, 6)
    want = rnea(model, q, q, q)
    for _ in range(PROMOTE_AFTER):
        rnea(model, q, q, q)
    assert native.COMPILER.wait(timeout=120.0)
    kernel = kernels_of(model).rnea
    assert kernel.native is not None
    calls = python_calls(monkeypatch, [kernel])
    got = rnea(model, q, q, q)
    assert calls == []  # the native form answered
    np.testing.assert_array_equal(got, want)


def test_results_are_arrays_of_their_own():
    model = promoted(offset_arm())
    q = np.zeros(6)
    first, second = rnea(model, q, q, q), rnea(model, q + 0.5, q, q)
    kept = first.copy()
    first += 1.0  # writable, and writing to it changes no other result
    np.testing.assert_array_equal(first - 1.0, kept)
    assert not np.array_equal(second, kept)
    M = mass_matrix(model, q)
    assert M.shape == (6, 6) and M.flags.writeable
    np.testing.assert_array_equal(M, M.T)


def test_non_finite_inputs_and_results_are_refused_as_by_the_python_form():
    model = promoted(offset_arm())
    q = np.zeros(6)
    with pytest.raises(ValueError, match="qd: must be finite"):
        rnea(model, q, np.array([0.0, np.inf, 0, 0, 0, 0]), q)
    with pytest.raises(ValueError, match="q: must be finite"):
        gravity(model, np.full(6, np.nan))
    with pytest.raises(ValueError, match="q: must be finite"):
        mass_matrix(model, np.full(6, np.nan))
    with pytest.raises(ValueError, match="rnea: the result is not finite"):
        rnea(model, q, np.full(6, 1e200), q)


def test_friction_is_inside_the_native_torques_and_a_flange_wrench_takes_the_python_form(monkeypatch):
    def with_friction():
        model = irb140(payload=OFFSET_PAYLOAD)
        return replace(model, joints=tuple(replace(j, friction=Friction(0.5, 2.0)) for j in model.joints))

    model, python_model = promoted(with_friction(), (WITH_FRICTION,)), with_friction()
    assert model.friction is not None
    calls = python_calls(monkeypatch, [kernels_of(model).rnea_with_friction])
    for q, qd, qdd in zip(*states(model, count=50, seed=8)):
        np.testing.assert_array_equal(rnea(model, q, qd, qdd), rnea(python_model, q, qd, qdd))
    assert calls == []  # the native form answered, friction added
    q = np.full(6, 0.3)
    wrench = np.arange(6.0)
    np.testing.assert_array_equal(rnea(model, q, q, q, wrench), rnea(python_model, q, q, q, wrench))


def test_without_a_compiler_or_when_disabled_everything_stays_python(monkeypatch):
    monkeypatch.setenv("IRB140_NATIVE", "0")
    assert not native.enabled()
    model = offset_arm()
    q = np.full(6, 0.2)
    for _ in range(PROMOTE_AFTER + 1):
        rnea(model, q, q, q)
    assert native.COMPILER.wait(timeout=120.0)
    assert kernels_of(model).rnea.native is None
    monkeypatch.setenv("IRB140_NATIVE", "1")
    monkeypatch.setattr(library.shutil, "which", lambda name: None)
    assert native.c_compiler() is None and not native.enabled()
    assert prepare(model).reason == "no C compiler"


def test_a_compile_that_fails_leaves_the_python_form(monkeypatch):
    monkeypatch.setattr(library, "FLAGS", (*library.FLAGS, "--no-such-flag"))
    model = frictionless(irb140(payload=OFFSET_PAYLOAD).with_gravity((0.0, 0.1, -9.8)))
    kernels = kernels_of(model)
    done = prepare(model, timeout=120.0, names=("gravity_torques",))
    assert not done.native and not done.compiling and done.reason.startswith("not compiled")
    assert kernels.gravity_torques.native is None
    q = np.full(6, 0.4)
    np.testing.assert_array_equal(gravity(model, q), np.array(kernels.gravity_torques.scalar(q.tolist())))


def test_a_library_is_compiled_once_and_then_loaded_from_the_cache():
    source, _, _ = c_code.kernel_source(kernels_of(irb140(payload=OFFSET_PAYLOAD)).gravity_torques.program)
    path = library.library(source)
    stamp = path.stat().st_mtime_ns
    assert library.library(source) == path and path.stat().st_mtime_ns == stamp
    assert path.parent == native.cache_dir() and str(path).startswith(os.environ["IRB140_CACHE"])


def test_waiting_with_nothing_asked_for_returns_at_once():
    assert compiler.Compiler().wait(timeout=30.0)  # was: no worker thread, so the timeout


def test_the_check_before_use_compares_bits():
    python = lambda q, k=(): [0.0, 1.0]  # noqa: E731
    native_form = lambda q: np.array([-0.0, 1.0])  # noqa: E731
    assert not compiler.same_as_python(native_form, python, [1], 0)
    assert compiler.same_as_python(lambda q: np.array([0.0, 1.0]), python, [1], 0)


@pytest.mark.parametrize("damage", ["truncated", "emptied", "garbage"])
def test_a_damaged_library_in_the_cache_is_compiled_again(damage):
    source, _, _ = c_code.kernel_source(kernels_of(irb140(payload=OFFSET_PAYLOAD)).gravity_torques.program)
    path = library.library(source)
    whole = path.read_bytes()
    path.unlink()  # a new file: this process may have the library loaded, and writing into it would crash it
    path.write_bytes({"truncated": whole[: len(whole) // 2], "emptied": b"", "garbage": b"x" * len(whole)}[damage])
    assert library.library(source) == path and path.read_bytes() == whole  # loading it could crash (SIGBUS)
    assert compiler.load(source) is not None


def test_stale_working_folders_are_removed_by_a_compile(monkeypatch, tmp_path):
    monkeypatch.setenv("IRB140_CACHE", str(tmp_path))  # a cache of its own: the run's workers share theirs
    folder = native.cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    old, recent = folder / f"{library.WORKING_PREFIX}old", folder / f"{library.WORKING_PREFIX}recent"
    for work in (old, recent):
        work.mkdir()
        (work / "kernel.c").write_text("")
    os.utime(old, (0, time.time() - library.STALE_AFTER - 10.0))
    monkeypatch.setattr(library, "FLAGS", (*library.FLAGS, "-DSTALE_TEST"))  # not cached: compiled
    library.library(c_code.kernel_source(kernels_of(irb140()).gravity_torques.program)[0])
    assert not old.exists() and recent.exists()
    shutil.rmtree(recent)


@pytest.mark.parametrize("cc", ["true", "false"])
def test_a_cc_that_is_not_a_compiler_leaves_the_python_form(monkeypatch, tmp_path, cc):
    monkeypatch.setenv("CC", shutil.which(cc))
    monkeypatch.setenv("IRB140_CACHE", str(tmp_path))  # a cache of its own: the run's workers share theirs
    model = frictionless(irb140().with_gravity((0.0, 0.3, -9.7)))
    done = prepare(model, timeout=120.0, names=("gravity_torques",))
    assert not done.native and kernels_of(model).gravity_torques.native is None
    folder = native.cache_dir()  # made by a compile tried, if any
    assert not folder.exists() or not [p for p in folder.iterdir() if p.name.startswith(library.WORKING_PREFIX)]


def test_a_forked_child_computes_and_waits():
    model, python_model = promoted(offset_arm()), offset_arm()
    q = np.full(6, 0.7)
    pid = os.fork()
    if pid == 0:  # the child: no worker thread until asked; exit code 0 if all right
        right = np.array_equal(rnea(model, q, q, q), rnea(python_model, q, q, q))
        os._exit(0 if right and native.COMPILER.wait(timeout=30.0) else 1)
    assert os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]) == 0


EXITING = """
import sys, time
from irb140_dynamics.core import irb140
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.native import COMPILER, cache_dir, library
COMPILER.request(kernels_of(irb140()).gravity_torques)
while not list(cache_dir().glob(library.WORKING_PREFIX + "*/started")):
    time.sleep(0.02)
sys.exit(0)  # during the compile
"""


def test_exiting_during_a_compile_leaves_nothing(tmp_path):
    compiler = tmp_path / "slow-cc"  # a compiler that takes its time
    compiler.write_text(f"#!/bin/sh\necho $$ > {tmp_path}/pid\ntouch started\nexec sleep 60\n")
    compiler.chmod(0o755)
    cache = tmp_path / "cache"
    env = {**os.environ, "CC": str(compiler), "IRB140_CACHE": str(cache)}
    done = subprocess.run([sys.executable, "-c", EXITING], env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stderr == ""
    assert list((cache / "irb140_dynamics" / "kernels").iterdir()) == []  # no working folder
    assert not running(int((tmp_path / "pid").read_text())), "the compiler outlived the process"


def running(pid: int) -> bool:
    """Whether process ``pid`` is alive (not gone or a zombie) 5 s from now at the latest."""
    for _ in range(100):
        try:
            if Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z":
                return False
        except FileNotFoundError:
            return False
        time.sleep(0.05)
    return True


def test_a_cache_folder_others_can_write_to_is_not_used(tmp_path, monkeypatch):
    shared = tmp_path / "shared"
    (shared / "irb140_dynamics" / "kernels").mkdir(parents=True)
    (shared / "irb140_dynamics" / "kernels").chmod(0o777)
    monkeypatch.setenv("IRB140_CACHE", str(shared))
    source, _, _ = c_code.kernel_source(kernels_of(irb140()).gravity_torques.program)
    with pytest.raises(OSError, match="not private to this user"):
        library.library(source)
    assert list((shared / "irb140_dynamics" / "kernels").iterdir()) == []


def test_without_python_headers_the_kernels_are_called_through_ctypes(monkeypatch):
    monkeypatch.setattr(compiler, "headers", lambda: None)
    with installed(compiler.Compiler()):  # nothing built by this process yet
        model = promoted(offset_arm())
    assert isinstance(kernels_of(model).rnea.native, compiler.CtypesKernel)
    assert kernels_of(model).rnea.native_batch is None  # no batch form: the batch verbs take NumPy's
    python_model = offset_arm()
    for q, qd, qdd in zip(*states(model, count=50)):
        np.testing.assert_array_equal(rnea(model, q, qd, qdd), rnea(python_model, q, qd, qdd))
        np.testing.assert_array_equal(mass_matrix(model, q), mass_matrix(python_model, q))
    assert kernels_of(model).rnea.native(q.tolist(), qd, qdd) is None  # not arrays: the Python form's


def test_prepare_compiles_now_and_the_verbs_then_answer_natively(monkeypatch):
    model = irb140(payload=RigidBody(2.5, (0.01, 0.0, 0.05)))
    done = prepare(model, timeout=120.0)
    assert done.native and not done.compiling and done.seconds > 0.0 and done.reason is None
    kernels = kernels_of(model)
    calls = python_calls(monkeypatch, [kernels.kernel(name) for name in NATIVE_KERNELS])
    q = np.full(6, 0.4)
    python_model = irb140(payload=RigidBody(2.5, (0.01, 0.0, 0.05)))
    with native_off():
        want = rnea(python_model, q, q, q), gravity(python_model, q), mass_matrix(python_model, q)
    for got, expected in zip((rnea(model, q, q, q), gravity(model, q), mass_matrix(model, q)), want):
        np.testing.assert_array_equal(got, expected)
    assert calls == []  # native answered
    assert prepare(model).native  # already: at once


def test_prepare_without_native_code_says_so(monkeypatch):
    monkeypatch.setenv("IRB140_NATIVE", "0")
    done = prepare(irb140().with_gravity((0.0, 0.2, -9.8)), timeout=60.0)
    assert not done.native and not done.compiling and done.reason == "IRB140_NATIVE=0"


def test_prepare_past_its_timeout_leaves_the_compile_running_and_python_answering(tmp_path, monkeypatch):
    slow = tmp_path / "slow-cc"  # a compiler that takes its time
    slow.write_text(f'#!/bin/sh\nsleep 3\nexec {native.c_compiler()} "$@"\n')
    slow.chmod(0o755)
    monkeypatch.setenv("CC", str(slow))
    model = irb140().with_gravity((0.1, -0.2, -9.8))  # a pattern of zeros no other test compiles
    done = prepare(model, timeout=0.5, names=("gravity_torques",))
    assert not done.native and done.compiling and done.seconds < 3.0 and done.reason == "compiling"
    q = np.full(6, 0.1)
    np.testing.assert_array_equal(gravity(model, q), np.array(kernels_of(model).gravity_torques.scalar(q.tolist())))
    assert native.COMPILER.wait(timeout=120.0)
    assert kernels_of(model).gravity_torques.native is not None  # in the background, done


@contextlib.contextmanager
def installed(compiler):
    """``compiler`` the one the core asks, in this block."""
    native_hook.install(compiler)
    try:
        yield
    finally:
        native_hook.install(native.COMPILER)


@contextlib.contextmanager
def native_off():
    before = os.environ.get("IRB140_NATIVE")
    os.environ["IRB140_NATIVE"] = "0"
    try:
        yield
    finally:
        os.environ.pop("IRB140_NATIVE") if before is None else os.environ.__setitem__("IRB140_NATIVE", before)


def test_the_extension_takes_any_float64_vector_and_leaves_the_rest_to_the_python_form():
    model = promoted(offset_arm())
    python_model = offset_arm()
    Q = np.random.default_rng(4).uniform(-2.0, 2.0, (6, 3))
    column = Q[:, 1]  # strided
    readonly = Q[:, 2].copy()
    readonly.flags.writeable = False
    swapped = Q[:, 0].astype(">f8")
    for q in (column, readonly, swapped, Q[:, 0].astype(np.float32), Q[:, 0].tolist()):
        want = rnea(python_model, np.array(q, dtype=float), column, readonly)
        np.testing.assert_array_equal(rnea(model, q, column, readonly), want)
        np.testing.assert_array_equal(mass_matrix(model, q), mass_matrix(python_model, np.array(q, dtype=float)))
    native_rnea = kernels_of(model).rnea.native
    assert native_rnea(swapped, column, readonly) is None  # byte-swapped: the Python form converts it
    assert native_rnea(column, column) is None and native_rnea(Q, Q, Q) is None
    assert native_rnea(column, column, column) is not None


def test_a_model_of_an_arm_compiled_before_is_ready_and_native_at_once():
    promoted(irb140(payload=RigidBody(1.5)), NATIVE_KERNELS)
    other = kernels_of(irb140(payload=RigidBody(4.0)))  # another payload mass: the same code
    assert other.ready() and other.is_native(*NATIVE_KERNELS)  # bound to it, nothing compiled
    heavier = irb140().to_params() | {"joint_2.link.mass": float(np.random.default_rng().uniform(31.0, 39.0))}
    fresh = kernels_of(RobotModel.from_params(heavier))  # an arm nothing has traced yet
    assert not fresh.ready()
