"""The generated C and Python equal the numeric core: tau, M, g and C(q, qd) qd at 1,000
random states, on the IRB-140, the IRB-140 with 6 kg on its flange, the UR5 and the Panda
(7 joints), to 1e-9 of each state's largest entry; the report's stretched-pose torques to
every printed digit; the regressor; symbolic parameters (the payload's on a turned flange).

Each arm's code is generated once for the module (C and Python from one derivation).
"""

import numpy as np
import pytest

from irb140_dynamics.core import (
    RigidBody,
    coriolis_batch,
    gravity_batch,
    mass_matrix_batch,
    rnea,
    rnea_batch,
)
from irb140_dynamics.core.equations import derive, generate
from irb140_dynamics.core.regressor import regressor_batch

from .support import arms, assert_close, c_function, compile_c, compiler, import_file, random_states

pytestmark = pytest.mark.slow  # generation: seconds per arm

ARMS = arms()
STRETCHED = [0.0, -np.pi / 2, np.pi / 2, 0.0, 0.0, 0.0]
# The report's torques at the stretched pose, q_dot = q_ddot = 0, as printed (REFERENCE.md)
REPORT = {
    "irb140": ("0", "243.382", "79.1556", "0", "2.43004", "0"),
    "irb140_6kg": ("0", "290.765", "105.348", "0", "6.25594", "0"),
}


_GENERATED = {}


def generated_arm(name, tmp_path_factory):
    """(name, model, Python module, C library or None) of one arm, generated once per module."""
    if name not in _GENERATED:
        model = ARMS[name]
        folder = tmp_path_factory.mktemp(f"equations_{name}")
        for file, text in generate(model, ("c", "python"), prefix=name).items():
            (folder / file).write_text(text)
        module = import_file(folder / f"{name}_eom.py", f"generated_{name}")
        library = compile_c(folder, name) if compiler() else None
        _GENERATED[name] = name, model, module, library
    return _GENERATED[name]


@pytest.fixture(scope="module", params=sorted(ARMS))
def generated(request, tmp_path_factory):
    return generated_arm(request.param, tmp_path_factory)


def reference(model, Q, QD, QDD):
    return {
        "tau": rnea_batch(model, Q, QD, QDD),
        "M": mass_matrix_batch(model, Q),
        "g": gravity_batch(model, Q),
        "Cqd": coriolis_batch(model, Q, QD),
    }


def test_python_equals_the_core(generated):
    name, model, module, _ = generated
    Q, QD, QDD = random_states(model.n)
    want = reference(model, Q, QD, QDD)
    got = {"tau": module.tau(Q, QD, QDD), "M": module.M(Q), "g": module.g(Q), "Cqd": module.Cqd(Q, QD)}
    for quantity in want:
        assert_close(got[quantity], want[quantity], f"{name} {quantity} (Python, batch)")
    # one state: shapes (n,) and (n, n)
    assert_close(module.tau(Q[0], QD[0], QDD[0])[None], want["tau"][:1], f"{name} tau (Python, one state)")
    assert module.M(Q[0]).shape == (model.n, model.n)


def test_c_equals_the_core(generated):
    name, model, _, library = generated
    if library is None:
        pytest.skip("no C compiler (cc or gcc) on this machine: the generated C is not compiled")
    n = model.n
    Q, QD, QDD = random_states(model.n, seed=1)
    want = reference(model, Q, QD, QDD)
    functions = {
        "tau": (c_function(library, f"{name}_tau", 3, n), (Q, QD, QDD)),
        "M": (c_function(library, f"{name}_M", 1, n * n), (Q,)),
        "g": (c_function(library, f"{name}_g", 1, n), (Q,)),
        "Cqd": (c_function(library, f"{name}_Cqd", 2, n), (Q, QD)),
    }
    for quantity, (fn, inputs) in functions.items():
        got = np.array([fn(*state) for state in zip(*inputs)])
        assert_close(got.reshape(want[quantity].shape), want[quantity], f"{name} {quantity} (C)")


@pytest.mark.parametrize("arm", sorted(REPORT))
def test_the_reports_stretched_pose_torques_to_every_printed_digit(arm, tmp_path_factory):
    _, _, module, library = generated_arm(arm, tmp_path_factory)
    zeros = np.zeros(6)
    results = {"Python g": module.g(STRETCHED), "Python tau": module.tau(STRETCHED, zeros, zeros)}
    if library is not None:
        results["C g"] = c_function(library, f"{arm}_g", 1, 6)(STRETCHED)
        results["C tau"] = c_function(library, f"{arm}_tau", 3, 6)(STRETCHED, zeros, zeros)
    for what, torques in results.items():
        for joint, (printed, value) in enumerate(zip(REPORT[arm], torques)):
            decimals = len(printed.partition(".")[2])
            assert abs(value - float(printed)) <= 0.5 * 10.0**-decimals, f"{arm} {what} joint {joint + 1}: {value}"


def test_regressor_equals_the_core(tmp_path):
    model = ARMS["irb140_6kg"]
    files = generate(model, ("c", "python"), what=("regressor",), prefix="arm")
    for file, text in files.items():
        (tmp_path / file).write_text(text)
    module = import_file(tmp_path / "arm_eom.py", "generated_regressor")
    Q, QD, QDD = random_states(model.n, seed=2, count=200)
    want = regressor_batch(model, Q, QD, QDD)
    assert_close(module.regressor(Q, QD, QDD), want, "regressor (Python)")
    if compiler():
        fn = c_function(compile_c(tmp_path, "arm"), "arm_regressor", 3, want[0].size)
        got = np.array([fn(*state) for state in zip(Q, QD, QDD)]).reshape(want.shape)
        assert_close(got, want, "regressor (C)")


def test_symbolic_parameters_take_any_values(tmp_path):
    """The UR5's code with symbolic parameters, derived without payload, evaluated with the
    parameters of the UR5 carrying a payload off-centre on its turned tool0 flange."""
    arm = ARMS["ur5"]
    loaded = arm.with_payload(RigidBody(2.5, (0.01, -0.02, 0.05), (0.004, 0.005, 0.006, 0.0002, -0.0001, 0.0003)))
    assert not arm.flange.is_identity
    files = generate(arm, ("c", "python"), symbolic=True, prefix="ur5")
    for file, text in files.items():
        (tmp_path / file).write_text(text)
    module = import_file(tmp_path / "ur5_eom.py", "generated_symbolic")
    p = np.array([x.value for x in derive(loaded, (), symbolic=True).parameters])  # the values alone
    assert not np.array_equal(p, module.PARAMETERS)
    Q, QD, QDD = random_states(arm.n, seed=3, count=200)
    for model, values in ((arm, module.PARAMETERS), (loaded, p)):
        want = reference(model, Q, QD, QDD)
        got = {
            "tau": module.tau(Q, QD, QDD, values),
            "M": module.M(Q, values),
            "g": module.g(Q, values),
            "Cqd": module.Cqd(Q, QD, values),
        }
        for quantity in want:
            assert_close(got[quantity], want[quantity], f"symbolic {quantity}")
    if compiler():
        fn = c_function(compile_c(tmp_path, "ur5"), "ur5_tau", 3, arm.n, n_parameters=len(p))
        got = np.array([fn(*state, p=p) for state in zip(Q, QD, QDD)])
        assert_close(got, rnea_batch(loaded, Q, QD, QDD), "symbolic tau (C)")


def test_friction_is_in_tau(tmp_path):
    """A model with friction: the generated tau carries it (tanh-smoothed Coulomb) as rnea does."""
    from dataclasses import replace

    from irb140_dynamics.core import Friction

    model = ARMS["irb140"]
    model = replace(
        model, joints=tuple(replace(j, friction=Friction(0.5 + k, 2.0 + k)) for k, j in enumerate(model.joints))
    )
    files = generate(model, ("python",), what=("tau",), prefix="arm")
    (tmp_path / "arm_eom.py").write_text(files["arm_eom.py"])
    module = import_file(tmp_path / "arm_eom.py", "generated_friction")
    Q, QD, QDD = random_states(model.n, seed=4, count=200)
    QD[:5] *= 1e-3  # near zero velocity, where the tanh bends
    assert_close(module.tau(Q, QD, QDD), rnea_batch(model, Q, QD, QDD), "tau with friction")
    assert np.allclose(module.tau(Q[0], QD[0], QDD[0]), rnea(model, Q[0], QD[0], QDD[0]), rtol=1e-9)
