"""An arm with a prismatic joint: the generated C and Python equal the numeric core (the
symbolic runner calls the same recursions as the core, so it follows their joint kinds).
Skipped, with the loader's reason, while the core loads revolute joints only."""

import numpy as np
import pytest

from irb140_dynamics.core import coriolis_batch, gravity_batch, mass_matrix_batch, rnea_batch
from irb140_dynamics.core.equations import generate

from .support import assert_close, c_function, compile_c, compiler, import_file, prismatic_arm, random_states

MODEL, WHY_NOT = prismatic_arm()
pytestmark = pytest.mark.skipif(MODEL is None, reason=str(WHY_NOT))


@pytest.mark.parametrize("symbolic", [False, True])
def test_prismatic_arm_equals_the_core(tmp_path, symbolic):
    files = generate(MODEL, ("c", "python"), symbolic=symbolic, prefix="slider")
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    module = import_file(tmp_path / "slider_eom.py", f"generated_slider_{symbolic}")
    n = MODEL.n
    Q, QD, QDD = random_states(n, seed=7)
    Q[:, 1] = np.abs(Q[:, 1]) / 10  # the slide's travel, m
    want = {
        "tau": rnea_batch(MODEL, Q, QD, QDD),
        "M": mass_matrix_batch(MODEL, Q),
        "g": gravity_batch(MODEL, Q),
        "Cqd": coriolis_batch(MODEL, Q, QD),
    }
    got = {"tau": module.tau(Q, QD, QDD), "M": module.M(Q), "g": module.g(Q), "Cqd": module.Cqd(Q, QD)}
    for quantity in want:
        assert_close(got[quantity], want[quantity], f"prismatic {quantity} (Python)")
    if compiler():
        library = compile_c(tmp_path, "slider")
        extra = {"n_parameters": len(module.PARAMETERS)} if symbolic else {}
        p = {"p": module.PARAMETERS} if symbolic else {}
        tau = c_function(library, "slider_tau", 3, n, **extra)
        M = c_function(library, "slider_M", 1, n * n, **extra)
        assert_close(np.array([tau(*s, **p) for s in zip(Q, QD, QDD)]), want["tau"], "prismatic tau (C)")
        assert_close(np.array([M(q, **p) for q in Q]).reshape(-1, n, n), want["M"], "prismatic M (C)")
