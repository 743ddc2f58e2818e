"""The derivatives and M^-1 that ``equations`` writes in C (--what dtau,qdd,dqdd,Minv) are
the kernels' arithmetic: compiled with warnings as errors, they give the numbers of
rnea_derivatives, forward_dynamics_derivatives, inverse_mass_matrix and the forward
dynamics kernel bit for bit. On the IRB-140 those run native (the derivative kernels'
C, compiled by the package, and its matrices returned apart); on the Panda their Python
form, which any native form must equal bit for bit before it is used (test_native_kernels)."""

import ctypes
from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics import native
from irb140_dynamics.core import (
    DERIVATIVE_KERNELS,
    Friction,
    forward_dynamics,
    forward_dynamics_derivatives,
    inverse_mass_matrix,
    irb140,
    prepare,
    rnea_derivatives,
)
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.core.equations import generate
from irb140_dynamics.native import library

from ...support.common import OFFSET_PAYLOAD
from .support import arms, compile_c, compiler, random_states

pytestmark = pytest.mark.skipif(compiler() is None, reason="no C compiler (cc or gcc) on this machine")

WHAT = ("dtau", "qdd", "dqdd", "Minv")
STATES = 20  # random states compared bit for bit
QDD_KERNEL = "forward_dynamics_qdd"


def with_coulomb_friction():
    model = irb140(payload=OFFSET_PAYLOAD)
    return replace(
        model, joints=tuple(replace(j, friction=Friction(0.4 + 0.1 * i, 1.5)) for i, j in enumerate(model.joints))
    )


def c_call(library, name: str, inputs: int, outputs: list[int]):
    """The C function ``name``: arrays in -> its output arrays."""
    fn = getattr(library, name)
    fn.restype = None
    double_p = ctypes.POINTER(ctypes.c_double)

    def call(*arrays):
        outs = [np.empty(size) for size in outputs]
        fn(*(np.ascontiguousarray(a, dtype=float).ctypes.data_as(double_p) for a in arrays[:inputs]),
           *(out.ctypes.data_as(double_p) for out in outs))  # fmt: skip
        return outs

    return call


@pytest.fixture(autouse=True)
def compiles_at_normal_priority(monkeypatch):
    monkeypatch.setattr(library, "NICENESS", 0)


@pytest.mark.parametrize("arm", ["irb140 with Coulomb friction and an offset payload", "panda (URDF damping)"])
def test_the_written_derivatives_are_the_native_kernels_arithmetic(tmp_path, arm):
    model = with_coulomb_friction() if arm.startswith("irb140") else arms()["panda"]
    files = generate(model, ("c",), what=WHAT, prefix="arm")
    header = files["arm_eom.h"]
    n = model.n
    for signature in (
        f"void arm_dtau(const double q[{n}], const double qd[{n}], const double qdd[{n}], "
        f"double dtau_dq[{n * n}], double dtau_dqd[{n * n}]);",
        f"void arm_qdd(const double q[{n}], const double qd[{n}], const double tau[{n}], double qdd[{n}]);",
        f"void arm_dqdd(const double q[{n}], const double qd[{n}], const double tau[{n}], "
        f"double dqdd_dq[{n * n}], double dqdd_dqd[{n * n}]);",
        f"void arm_Minv(const double q[{n}], double Minv[{n * n}]);",
    ):
        assert signature in header
    for file, text in files.items():
        (tmp_path / file).write_text(text)
    library = compile_c(tmp_path, "arm")
    dtau, qdd = c_call(library, "arm_dtau", 3, [n * n, n * n]), c_call(library, "arm_qdd", 3, [n])
    dqdd, Minv = c_call(library, "arm_dqdd", 3, [n * n, n * n]), c_call(library, "arm_Minv", 1, [n * n])

    names = (*DERIVATIVE_KERNELS, QDD_KERNEL)
    kernels = kernels_of(model)
    if native.enabled() and arm.startswith("irb140"):
        assert prepare(model, timeout=600.0, names=names).native
    forward = kernels.forward_dynamics_qdd
    for q, qd, x in zip(*random_states(n, seed=5, count=STATES)):
        tau = 10.0 * x
        dq, dqd, _ = rnea_derivatives(model, q, qd, x)
        assert [m.tobytes() for m in dtau(q, qd, x)] == [dq.tobytes(), dqd.tobytes()]
        A, B, inverse = forward_dynamics_derivatives(model, q, qd, tau)
        assert [m.tobytes() for m in dqdd(q, qd, tau)] == [A.tobytes(), B.tobytes()]
        assert Minv(q)[0].tobytes() == inverse_mass_matrix(model, q).tobytes()
        want = forward.native(q, qd, tau) if forward.native is not None else np.array(forward.scalar(q, qd, tau))
        assert qdd(q, qd, tau)[0].tobytes() == want.tobytes()
        np.testing.assert_allclose(want, forward_dynamics(model, q, qd, tau), rtol=1e-9, atol=1e-9)


def test_the_derivatives_are_c_only_and_numeric():
    model = irb140()
    for forms, symbolic in ((("python",), False), (("latex",), False), (("c",), True)):
        with pytest.raises(
            ValueError, match="^dqdd: the derivatives are written in the C form of a model with numbers"
        ):
            generate(model, forms, what=("tau", "dqdd"), symbolic=symbolic)
