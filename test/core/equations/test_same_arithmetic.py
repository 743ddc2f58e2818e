"""The C that ``equations`` writes is the code generator's: its tau (friction included),
M, g and C(q, qd) qd equal the core's public functions bit for bit, as the native kernels
a node calls do (test_native_kernels)."""

from dataclasses import replace

import pytest

from irb140_dynamics.core import Friction, coriolis, gravity, irb140, mass_matrix, rnea
from irb140_dynamics.core.equations import generate
from irb140_dynamics.core.urdf import load_urdf

from ...support.common import OFFSET_PAYLOAD
from ..test_urdf_trees import TWO_ARMS
from .support import arms, c_function, compile_c, compiler, random_states

pytestmark = pytest.mark.skipif(compiler() is None, reason="no C compiler (cc or gcc) on this machine")


def with_friction():
    model = irb140(payload=OFFSET_PAYLOAD)
    return replace(
        model, joints=tuple(replace(j, friction=Friction(0.4 + 0.1 * i, 1.5)) for i, j in enumerate(model.joints))
    )


ARMS = {
    "irb140 with friction and an offset payload": with_friction,
    "panda (URDF damping)": lambda: arms()["panda"],
    # two arms on a torso, mimic joints (one before its joint in the file, one prismatic with
    # an offset; damping on one) as in test_urdf_trees
    "a tree with mimic joints": lambda: load_urdf(TWO_ARMS).model,
}


@pytest.mark.parametrize(
    "arm",
    [
        pytest.param(arm, marks=pytest.mark.slow)
        if arm.startswith("a tree")
        else arm  # its symbolic derivation: seconds
        for arm in ARMS
    ],
)
def test_the_written_c_is_the_cores_arithmetic(tmp_path, arm):
    model = ARMS[arm]()
    assert model.friction is not None
    for file, text in generate(model, ("c",), prefix="arm").items():
        (tmp_path / file).write_text(text)
    library = compile_c(tmp_path, "arm")
    n = model.n
    tau, M = c_function(library, "arm_tau", 3, n), c_function(library, "arm_M", 1, n * n)
    g, Cqd = c_function(library, "arm_g", 1, n), c_function(library, "arm_Cqd", 2, n)
    for q, qd, qdd in zip(*random_states(n, seed=3, count=100)):
        assert tau(q, qd, qdd).tobytes() == rnea(model, q, qd, qdd).tobytes()
        assert M(q).tobytes() == mass_matrix(model, q).tobytes()
        assert g(q).tobytes() == gravity(model, q).tobytes()
        assert Cqd(q, qd).tobytes() == coriolis(model, q, qd).tobytes()
