"""An arm's kernels are an object a caller holds (as Pinocchio's ``Data``), apart from the
model: ``Kernels(model)`` of its own, or ``kernels_of(model)``, the public verbs'. The core
computes without the compile room, which it reaches only through ``native_hook``."""

import gc
import pickle
import subprocess
import sys
import weakref
from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics import native, native_hook
from irb140_dynamics.core import Friction, gravity, irb140, mass_matrix, prepare, rnea
from irb140_dynamics.core.codegen.kernels import PROMOTE_AFTER, Kernels, kernels_of
from irb140_dynamics.core.codegen.recipes import RECIPES, WITH_FRICTION

from ..support.common import OFFSET_PAYLOAD
from ..support.paths import ROOT


def with_friction(model):
    return replace(model, joints=tuple(replace(j, friction=Friction(0.4, 1.5)) for j in model.joints))


def test_a_caller_holds_kernels_of_its_own_and_the_model_keeps_none():
    model = with_friction(irb140(payload=OFFSET_PAYLOAD))
    q, qd, qdd = np.full(6, 0.3), np.linspace(-1.0, 1.0, 6), np.full(6, -0.7)
    want = rnea(model, q, qd, qdd), gravity(model, q), mass_matrix(model, q)  # the verbs' kernels made
    assert not [value for value in vars(model).values() if isinstance(value, Kernels)]
    assert pickle.loads(pickle.dumps(model)) == model  # nothing of the kernels kept in it
    held = Kernels(model)
    assert held is not kernels_of(model) and kernels_of(model) is kernels_of(model)
    got = (
        held.rnea_with_friction.scalar(q.tolist(), qd.tolist(), qdd.tolist()),
        held.gravity_torques.scalar(q.tolist()),
        held.mass_matrix.scalar(q.tolist()),
    )
    np.testing.assert_array_equal(np.array(got[0]), want[0])  # bit for bit, friction inside
    np.testing.assert_array_equal(np.array(got[1]), want[1])
    np.testing.assert_array_equal(mass_matrix(model, q)[np.triu_indices(6)], np.array(got[2]))
    assert held.rnea_with_friction.program is not held.rnea.program  # the friction's own program


def test_every_kernel_is_an_attribute_and_a_name():
    kernels = Kernels(irb140())
    for name in [*RECIPES, WITH_FRICTION]:
        assert getattr(kernels, name) is kernels.kernel(name)
    assert Kernels(irb140()).rnea_with_friction is not None
    with pytest.raises(KeyError, match="no kernel 'rnae': one of rnea, "):
        kernels.kernel("rnae")
    with pytest.raises(AttributeError):
        kernels.rnae  # noqa: B018


def test_the_verbs_kernels_are_each_models_own_and_go_with_it():
    model = irb140(payload=OFFSET_PAYLOAD)
    equal = replace(model)
    assert equal == model and kernels_of(equal) is not kernels_of(model)
    q = np.full(6, 0.2)
    gravity(equal, q)
    kept = weakref.ref(kernels_of(equal))
    del equal
    gc.collect()
    assert kept() is None


CORE_ALONE = """
import sys
import numpy as np
from irb140_dynamics.core import coriolis, gravity, irb140, mass_matrix, rnea, rnea_batch
model, q = irb140(), np.full(6, 0.3)
for _ in range(3):
    rnea(model, q, q, q), gravity(model, q), mass_matrix(model, q), coriolis(model, q, q)
rnea_batch(model, np.zeros((4, 6)), np.zeros((4, 6)), np.zeros((4, 6)))
print([name for name in ("subprocess", "irb140_dynamics.native") if name in sys.modules])
"""


def test_the_core_computes_without_loading_the_compile_room():
    done = subprocess.run([sys.executable, "-c", CORE_ALONE], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["[]"]


def test_with_no_compiler_installed_prepare_says_so_and_the_python_form_answers(monkeypatch):
    monkeypatch.setattr(native_hook, "loader", None)
    native_hook.install(None)
    try:
        model = irb140().with_gravity((0.05, 0.25, -9.8))
        done = prepare(model, timeout=1.0)
        assert not done.native and not done.compiling and done.reason == "no compiler installed"
        assert kernels_of(model).ready()  # nothing would be compiled: at once
        q = np.full(6, 0.1)
        for _ in range(PROMOTE_AFTER + 1):  # the warm-up asks no one
            gravity(model, q)
        assert not kernels_of(model).is_native("gravity_torques")
        np.testing.assert_array_equal(gravity(model, q), kernels_of(model).gravity_torques.scalar(q.tolist()))
    finally:
        native_hook.install(native.COMPILER)


WARM_UP = """
import sys
import numpy as np
from irb140_dynamics.core import gravity, irb140, kernels_of
from irb140_dynamics.core.codegen.kernels import PROMOTE_AFTER
model, q = irb140(), np.full(6, 0.3)
for _ in range(PROMOTE_AFTER):
    gravity(model, q)
import threading
for thread in threading.enumerate():  # the warm-up's: it loads the compile room, then asks it
    if thread.name == "irb140-promote":
        thread.join(timeout=120.0)
import irb140_dynamics.native as native
native.COMPILER.wait(timeout=120.0)
print(kernels_of(model).is_native("gravity_torques"))
"""


@pytest.mark.skipif(not native.enabled(), reason="no C compiler (or IRB140_NATIVE=0)")
def test_in_a_fresh_process_the_warm_up_loads_the_compile_room_and_goes_native():
    done = subprocess.run([sys.executable, "-c", WARM_UP], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True"]
