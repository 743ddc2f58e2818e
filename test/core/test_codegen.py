"""Generated kernels: bit for bit the algorithms run on floats, and no folded-away terms left."""

import ast
from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics.core import Friction, coriolis, coriolis_matrix, gravity, irb140, mass_matrix, rnea
from irb140_dynamics.core.algorithms import derivatives
from irb140_dynamics.core.algorithms import recursions as algorithms
from irb140_dynamics.core.codegen.kernels import inputs_of, kernels_of
from irb140_dynamics.core.codegen.program import traced
from irb140_dynamics.core.codegen.python_code import compile_python
from irb140_dynamics.core.codegen.sincos import cosine, sine
from irb140_dynamics.core.codegen.trace import quarter_turned, quarter_turns

from ..support.common import OFFSET_PAYLOAD, loaded_irb140, model_makers, random_states

MODELS = model_makers(seed=300, sizes=(2, 7))


@pytest.fixture(scope="module", params=list(MODELS), ids=list(MODELS))
def robot(request):
    return MODELS[request.param]()


@pytest.fixture
def states(robot):
    Q, QD, QDD = random_states(np.random.default_rng(31), robot.n, 200)
    return [(q.tolist(), qd.tolist(), qdd.tolist()) for q, qd, qdd in zip(Q, QD, QDD)]


def angles(robot, q):
    """(cos, sin) of q_i + theta_offset_i on Python floats, as the kernels compute them: an
    offset of whole quarter turns as those of q_i turned (``trace.quarter_turns``)."""
    pairs = []
    for q_i, joint in zip(q, robot.joints):
        rest, m = quarter_turns(joint.offset)
        pairs.append(quarter_turned(cosine(q_i + rest), sine(q_i + rest), m))
    return pairs


def kernel_links(robot):
    """The links the kernels run on: the model's, regrouped (``Kernels``' own)."""
    kernels = kernels_of(robot)
    return kernels._arm.links_with(kernels.constants)


def test_rnea_kernels_are_the_algorithm_bit_for_bit(robot, states):
    links, zeros = kernel_links(robot), [0.0] * robot.n
    rng = np.random.default_rng(32)
    for q, qd, qdd in states:
        cs = angles(robot, q)
        assert rnea(robot, q, qd, qdd).tolist() == algorithms.rnea(links, cs, qd, qdd, robot.gravity)
        assert gravity(robot, q).tolist() == algorithms.rnea(links, cs, zeros, zeros, robot.gravity)
        assert coriolis(robot, q, qd).tolist() == algorithms.rnea(links, cs, qd, zeros, (0.0, 0.0, 0.0))
        wrench = rng.normal(0.0, 20.0, 6).tolist()
        direct = algorithms.rnea(links, cs, qd, qdd, robot.gravity, wrench[:3], wrench[3:])
        assert rnea(robot, q, qd, qdd, wrench).tolist() == direct


def test_equal_moments_of_inertia_take_one_input_and_their_difference_folds():
    """A link's equal moments of inertia in k share an input, so the traces fold their
    difference: the IRB-140's last link is symmetric about its axis, and its tau and M
    read no angle of joint 6; with an offset payload (not symmetric) tau does."""
    layout, values = inputs_of((2.0, 0.0, 3.0, 3.0, 4.0, 3.0, -9.81), (None, None, 1, 1, 1, 2, None))
    assert layout == (0, None, 1, 1, 2, 3, 4)
    assert values == (2.0, 3.0, 4.0, 3.0, -9.81)
    symmetric, offset = kernels_of(irb140()), kernels_of(irb140(payload=OFFSET_PAYLOAD))
    assert "q5" not in symmetric.rnea.program.inputs_used() | symmetric.mass_matrix.program.inputs_used()
    assert "q5" in offset.rnea.program.inputs_used()


def test_mass_matrix_kernel_is_crba_bit_for_bit(robot, states):
    links = kernel_links(robot)
    for q, _, _ in states:
        assert mass_matrix(robot, q).tolist() == algorithms.crba(links, angles(robot, q))


def test_coriolis_matrix_kernel_is_the_algorithm_bit_for_bit(robot, states):
    links = kernel_links(robot)
    for q, qd, _ in states[:50]:
        assert coriolis_matrix(robot, q, qd).tolist() == derivatives.christoffel_coriolis(links, angles(robot, q), qd)


KERNEL_INPUTS = {  # the argument groups after q, by kernel
    "rnea": ("qd", "qdd"),
    "rnea_wrench": ("qd", "qdd", "wrench"),
    "gravity_torques": (),
    "coriolis": ("qd",),
    "mass_matrix": (),
    "coriolis_matrix": ("qd",),
    "regressor": ("qd", "qdd"),
    "momentum": ("qd",),
}


@pytest.mark.parametrize("name", list(KERNEL_INPUTS))
def test_writing_array_form_is_the_array_form_bit_for_bit(robot, name):
    kernel = getattr(kernels_of(robot), name)
    rng = np.random.default_rng(33)
    Q, QD, QDD = random_states(rng, robot.n, 64)
    groups = [
        Q.T,
        *({"qd": QD.T, "qdd": QDD.T, "wrench": rng.normal(0.0, 20.0, (6, 64))}[g] for g in KERNEL_INPUTS[name]),
    ]
    expected = kernel.array(*groups)
    out = [np.full(64, np.nan) for _ in expected]
    kernel.into(out, *groups)
    for j in kernel.written:
        assert np.array_equal(out[j], np.broadcast_to(expected[j], 64)), f"output {j}"
    folded = set(range(len(expected))) - set(kernel.written)
    assert all(isinstance(expected[j], float) and np.isnan(out[j]).all() for j in folded)  # left to the caller


def trivial_operations(source: str) -> list[str]:
    """Multiplications by 0 or +-1 and additions or subtractions of 0 in generated code."""

    def literal(node):
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            value = literal(node.operand)
            return None if value is None else -value
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
            return node.value
        return None

    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.BinOp):
            operands = [literal(node.left), literal(node.right)]
            if isinstance(node.op, ast.Mult) and any(v in (0, 1, -1) for v in operands if v is not None):
                found.append(ast.unparse(node))
            if isinstance(node.op, (ast.Add, ast.Sub)) and 0 in [v for v in operands if v is not None]:
                found.append(ast.unparse(node))
    return found


def test_trivial_operation_finder_finds_them():
    assert trivial_operations("def f(x):\n    return (x * 1.0, 0.0 * x, x * (-1.0), x + 0.0, x * 2.0)\n") == [
        "x * 1.0",
        "0.0 * x",
        "x * -1.0",
        "x + 0.0",
    ]


def test_irb140_gravity_kernel_has_no_trivial_operations():
    source = kernels_of(irb140()).gravity_torques.source
    # joint 2's offset, a quarter turn, is a swap and a sign of q1's cos and sin: no addition
    assert "sin_cos_rows((q1, " in source and "1.5707963267948966" not in source
    assert trivial_operations(source) == []


@pytest.mark.parametrize("kernel", ["rnea", "rnea_wrench", "coriolis", "mass_matrix", "coriolis_matrix"])
def test_other_irb140_kernels_have_no_trivial_operations(kernel):
    assert trivial_operations(getattr(kernels_of(loaded_irb140()), kernel).source) == []


@pytest.mark.parametrize("coulomb", [0.0, 1.5])
def test_rnea_with_friction_adds_it_as_the_friction_model_does(coulomb):
    model = loaded_irb140()
    model = replace(
        model, joints=tuple(replace(j, friction=Friction(0.3 * i, coulomb)) for i, j in enumerate(model.joints))
    )
    kernels = kernels_of(model)
    for q, qd, qdd in zip(*random_states(np.random.default_rng(34), model.n, 100)):
        q, qd, qdd = q.tolist(), qd.tolist(), qdd.tolist()
        want = model.friction.added(kernels.rnea.scalar(q, qd, qdd), qd)
        assert list(kernels.rnea_with_friction.scalar(q, qd, qdd)) == want


def test_a_negation_costs_no_operation_where_an_operation_can_take_it():
    def algorithm(v):
        x, y, z = v
        product = -(x * y)  # a negation the tracer keeps, then read by a sum, a product and a constant
        return [(x - y) * z, (y - x) + z, product * z + y, z - product, product * 2.5, y + -(x * z) * (y * z)]

    program = traced("negations", algorithm, {"v": 3})
    ops = [op for op, _ in program.ops if op != "in"]
    # x - y, x * y, x * z, y * z, and the outputs' operations: y - x and every negation taken in
    assert len(ops) == 4 + 8 and "neg" not in ops
    on_floats = compile_python(program)[1](())
    rng = np.random.default_rng(5)
    for x, y, z in rng.normal(0.0, 3.0, (20, 3)).tolist():
        want = [(x - y) * z, (y - x) + z, -(x * y) * z + y, z + x * y, -(x * y) * 2.5, y - (x * z) * (y * z)]
        assert list(on_floats([x, y, z])) == want


def test_no_kernel_computes_a_difference_both_ways(robot):
    for name in ("rnea", "rnea_wrench", "mass_matrix", "rnea_derivatives"):
        program = kernels_of(robot).kernel(name).program
        differences = {args for op, args in program.ops if op == "-"}
        assert not [(a, b) for a, b in differences if a != b and (b, a) in differences], name
