"""The regressor of a model with mimic joints in every form the equations write: C, SymPy
and LaTeX here, the Python form through the ``equations`` tool (test/tools/test_tree_tools.py),
against the core's regressor (itself rnea's: test/core/test_regressor_mimic.py). GRIPPER: one
joint, two fingers following it on its link (a tree), a revolute one at -1x with an offset,
damping and Coulomb friction (its columns in the row of the joint it follows, m^2 qd and
tanh(qd/v_s)), a prismatic one at 0.5x with an offset and damping (no Coulomb term: |m| != 1)."""

import numpy as np
import sympy as sp

from irb140_dynamics.core.equations import generate
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.regressor import regressor_batch

from ..test_urdf_trees import _joint, _link
from .support import c_function, compile_c, compiler, import_file

FINGER_A = '<mimic joint="j1" multiplier="-1" offset="0.2"/><dynamics damping="0.2" friction="0.3"/>'
FINGER_B = '<mimic joint="j1" multiplier="0.5" offset="0.01"/><dynamics damping="0.4"/>'
GRIPPER = f"""<robot name="gripper"><link name="base"/>
  {_joint("j1", "base", "l1", axis="0 1 0")}{_link("l1", 2.0)}
  {_joint("fa", "l1", "fa", extra=FINGER_A)}{_link("fa", 0.3)}
  {_joint("fb", "l1", "fb", kind="prismatic", axis="0 0 1", extra=FINGER_B)}{_link("fb", 0.2)}
</robot>"""


def states(model, seed=40, count=3):
    rng = np.random.default_rng(seed)
    return tuple(rng.uniform(-1.0, 1.0, (count, model.n)) for _ in range(3))


def test_the_c_sympy_and_latex_regressor_of_mimic_joints_are_the_cores(tmp_path):
    model = load_urdf(GRIPPER).model
    assert model.n == 1 and len(model.joints) == 3
    files = generate(model, ("c", "sympy", "latex"), what=("regressor",), prefix="gripper")
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    Q, QD, QDD = states(model)
    want = regressor_batch(model, Q, QD, QDD)  # (3, 1, 39): 13 columns per link, the fingers' too
    assert want.shape == (3, 1, 39) and want[0, 0, 10 * 3 + 3 + 1] != 0.0  # finger a's Coulomb column
    if compiler():
        fn = c_function(compile_c(tmp_path, "gripper"), "gripper_regressor", 3, want[0].size)
        got = np.array([fn(*state) for state in zip(Q, QD, QDD)]).reshape(want.shape)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
    module = import_file(tmp_path / "gripper_eom_sympy.py", "gripper_eom_sympy")
    at = {**dict(zip(module.q, Q[0])), **dict(zip(module.qd, QD[0])), **dict(zip(module.qdd, QDD[0]))}
    got = np.array(module.regressor.subs(at).evalf(), dtype=float).reshape(want[0].shape)
    np.testing.assert_allclose(got, want[0], rtol=1e-12, atol=1e-12)
    assert len(module.REGRESSOR_COLUMNS) == 39 and "Y" in files["gripper_eom.tex"]
    assert all(isinstance(entry, sp.Expr) for entry in module.regressor)
