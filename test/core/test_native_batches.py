"""The batch verbs on native kernels (``Kernel.native_batch``: the C kernel in a loop over N
states): the NumPy form's numbers bit for bit, whatever the strides of the states' columns;
the NumPy form where the C declines (a result not finite), which then says the same; and
a batch call counts once toward making a kernel native. The session's cache is its own
(test/conftest.py)."""

import numpy as np
import pytest

from irb140_dynamics import native, native_hook
from irb140_dynamics.core import (
    RigidBody,
    coriolis_batch,
    forward_dynamics_batch,
    gravity_batch,
    irb140,
    mass_matrix_batch,
    prepare,
    rnea_batch,
)
from irb140_dynamics.core.codegen import kernels as kernel_module
from irb140_dynamics.core.codegen.kernels import PROMOTE_AFTER, kernels_of
from irb140_dynamics.core.dynamics import _evaluate, _symmetric
from irb140_dynamics.core.urdf import load_urdf
from irb140_dynamics.native import compiler, library

from ..support.common import OFFSET_PAYLOAD
from ..support.paths import URDF_DATA
from .test_native_kernels import python_calls

pytestmark = pytest.mark.skipif(native.c_compiler() is None, reason="no C compiler on this machine")

BATCH_KERNELS = ("rnea", "gravity_torques", "mass_matrix", "coriolis")  # what the batch verbs run
ARMS = {  # friction included: the batch verbs add it to the kernels' torques
    "irb140 with an offset payload": lambda: irb140(payload=OFFSET_PAYLOAD),
    "panda tree, a mimic finger": lambda: load_urdf((URDF_DATA / "panda.urdf").read_text()).model,
}


@pytest.fixture(autouse=True)
def compiles_at_normal_priority(monkeypatch):
    monkeypatch.setattr(library, "NICENESS", 0)


def native_model(arm: str):
    model = ARMS[arm]()
    done = prepare(model, timeout=120.0, names=BATCH_KERNELS)
    assert done.native, done
    assert all(kernels_of(model).kernel(name).native_batch is not None for name in BATCH_KERNELS)
    return model


def random_states(n: int, count: int, seed: int = 11):
    rng = np.random.default_rng(seed)
    return rng.uniform(-3.0, 3.0, (count, n)), rng.uniform(-3.0, 3.0, (count, n)), rng.uniform(-9.0, 9.0, (count, n))


def same_bits(got: np.ndarray, want: np.ndarray) -> bool:
    return got.shape == want.shape and got.dtype == want.dtype and got.tobytes() == want.tobytes()


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_the_batch_verbs_on_native_kernels_give_the_numpy_forms_bits(monkeypatch, arm):
    # python_model: kernels of its own, kept in their Python forms (the arm's calls counted
    # by earlier tests in this process do not promote them)
    monkeypatch.setattr(kernel_module, "PROMOTE_AFTER", 10**9)
    model, python_model = native_model(arm), ARMS[arm]()
    Q, QD, QDD = random_states(model.n, 300)
    calls = python_calls(monkeypatch, [kernels_of(model).kernel(name) for name in BATCH_KERNELS])
    for verb, args in (
        (rnea_batch, (Q, QD, QDD)),
        (gravity_batch, (Q,)),
        (coriolis_batch, (Q, QD)),
        (mass_matrix_batch, (Q,)),
        (forward_dynamics_batch, (Q, QD, QDD)),
        (gravity_batch, (Q[:1],)),
        (mass_matrix_batch, (Q[:0],)),
    ):
        assert same_bits(verb(model, *args), verb(python_model, *args)), verb.__name__
    assert calls == []  # the native forms answered
    assert kernels_of(python_model).gravity_torques.native_batch is None  # compared with NumPy indeed


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_native_batches_read_columns_through_any_strides(arm):
    kernels = kernels_of(native_model(arm))
    n = kernels.n
    X = np.random.default_rng(12).uniform(-3.0, 3.0, (401, 3 * n))
    views = {
        "transposed rows": [X[:, j * n : (j + 1) * n].T for j in range(3)],
        "every other state, backwards": [X[::-2, j * n : (j + 1) * n].T for j in range(3)],
        "contiguous": [np.ascontiguousarray(X[:, j * n : (j + 1) * n].T) for j in range(3)],
    }
    for name, (q, qd, qdd) in views.items():
        for kernel, columns in (
            (kernels.rnea, (q, qd, qdd)),
            (kernels.gravity_torques, (q,)),
            (kernels.coriolis, (q, qd)),
        ):
            assert same_bits(kernel.native_batch(*columns), _evaluate(kernel.array, *columns)), name
        M = kernels.mass_matrix
        assert same_bits(M.native_batch(q), _symmetric(_evaluate(M.array, q), n)), name
    q = views["contiguous"][0]
    gravity = kernels.gravity_torques.native_batch
    for refused in (q.astype(np.float32), q.astype(">f8"), q.tolist(), q[0], q[:-1], q[None]):
        assert gravity(refused) is None  # the NumPy form converts or refuses it
    assert kernels.rnea.native_batch(q, q, q[:, :-1]) is None  # not N states each
    assert kernels.rnea.native_batch(q, q) is None


def test_a_result_that_is_not_finite_takes_the_numpy_form_which_names_the_state():
    model, python_model = native_model("irb140 with an offset payload"), ARMS["irb140 with an offset payload"]()
    Q, QD, QDD = random_states(model.n, 50)
    QD[17] = 1e200  # finite, but its torques overflow
    for verb, args in ((rnea_batch, (Q, QD, QDD)), (coriolis_batch, (Q, QD))):
        with pytest.raises(ValueError) as python_error:
            verb(python_model, *args)
        assert "not finite at state 17" in str(python_error.value)
        with pytest.raises(ValueError, match=f"^{python_error.value}$"):
            verb(model, *args)
    rnea = kernels_of(model).rnea
    columns = (Q.T, QD.T, QDD.T)
    assert rnea.native_batch(*columns) is None  # declined for every state
    Q[3, 2] = np.nan
    with pytest.raises(ValueError, match=r"Q: must be finite \(state 3 is not\)"):
        gravity_batch(model, Q)
    assert kernels_of(model).gravity_torques.native_batch(Q.T) is None


def test_a_batch_call_counts_once_toward_making_the_arms_kernels_native(monkeypatch):
    model = irb140(payload=RigidBody(2.0, (0.0, 0.01, 0.08)))
    kernel = kernels_of(model).gravity_torques
    monkeypatch.setattr(kernel.trace, "calls", 0)  # the arm's count (other tests may have used it)
    asked = []
    compiler = native_hook.compiler()
    monkeypatch.setattr(compiler, "promote", lambda k, promote=compiler.promote: asked.append(k) or promote(k))
    Q = random_states(model.n, 40)[0]
    want = gravity_batch(model, Q)
    for _ in range(PROMOTE_AFTER - 2):
        gravity_batch(model, Q)
    assert asked == [] and kernel.native_batch is None  # 40 states a call: counted once each
    gravity_batch(model, Q)
    assert asked == [kernel]
    assert native.COMPILER.wait(timeout=120.0)
    assert kernel.native_batch is not None
    calls = python_calls(monkeypatch, [kernel])
    assert same_bits(gravity_batch(model, Q), want) and calls == []
    other = irb140(payload=RigidBody(3.0, (0.0, 0.02, 0.05)))  # the same arm, another payload
    want = gravity_batch(other, Q)  # its first call asks
    other_kernel = kernels_of(other).gravity_torques
    assert asked == [kernel, other_kernel] and native.COMPILER.wait(timeout=120.0)
    assert other_kernel.native_batch is not None and same_bits(gravity_batch(other, Q), want)


def test_with_native_off_the_batches_stay_numpy(monkeypatch):
    monkeypatch.setenv("IRB140_NATIVE", "0")
    model = irb140(payload=RigidBody(2.0, (0.0, 0.02, 0.08)))
    Q = random_states(model.n, 5)[0]
    for _ in range(PROMOTE_AFTER + 1):
        gravity_batch(model, Q)
    assert native.COMPILER.wait(timeout=120.0)
    kernel = kernels_of(model).gravity_torques
    assert kernel.native is None and kernel.native_batch is None


def test_the_check_before_use_compares_the_batch_forms_bits_too():
    python = lambda q, k=(): [0.0, 1.0]  # noqa: E731
    per_state = lambda q: np.array([0.0, 1.0])  # noqa: E731
    assert compiler.same_as_python(per_state, python, [1], 0, lambda q: np.tile([0.0, 1.0], (q.shape[1], 1)))
    assert not compiler.same_as_python(per_state, python, [1], 0, lambda q: np.tile([-0.0, 1.0], (q.shape[1], 1)))
    assert not compiler.same_as_python(per_state, python, [1], 0, lambda q: None)
