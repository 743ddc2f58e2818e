"""The C written on vectors of two doubles (codegen.pairs) is the core's arithmetic: on an
arm with no zero in its geometry (where pairs pay, and are written) tau and M equal rnea and
mass_matrix bit for bit, with GCC's vector extensions and, for other compilers, without."""

from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics.core import Friction, mass_matrix, rnea
from irb140_dynamics.core.codegen import pairs, sincos
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.core.codegen.pairs import paired_body, plan_pairs
from irb140_dynamics.core.codegen.program import with_constants
from irb140_dynamics.core.equations import generate

from ...support.common import random_urdf_model
from .support import c_function, compile_c, compiler, random_states

pytestmark = pytest.mark.skipif(compiler() is None, reason="no C compiler (cc or gcc) on this machine")


def generic_arm(n: int = 3):
    """n joints, every axis and angle generic (no right angle), full inertias, friction."""
    model = random_urdf_model(np.random.default_rng(11), n)
    joints = tuple(
        replace(
            joint,
            axis=tuple(np.array([0.3, -0.5, 0.8]) + 0.1 * i),
            origin=replace(joint.origin, rpy=(0.3 + 0.1 * i, -0.7, 1.1 - 0.2 * i)),
            friction=Friction(0.2 + 0.1 * i, 0.0),
        )
        for i, joint in enumerate(model.joints)
    )
    return replace(model, joints=joints)


@pytest.mark.parametrize("pairs", [True, False], ids=["vector pairs", "scalars"])
def test_the_paired_c_is_the_cores_arithmetic(tmp_path, pairs):
    model = generic_arm()
    files = generate(model, ("c",), what=("tau", "M"), prefix="arm")
    source = files["arm_eom.c"]
    assert "const sincos_pair p" in source  # the pairs are written here
    if not pairs:  # as a compiler without GCC's vector extensions reads it
        source = source.replace(sincos.C_SOURCE, sincos.C_SOURCE + "#undef SINCOS_PAIRS\n")
    files["arm_eom.c"] = source
    for file, text in files.items():
        (tmp_path / file).write_text(text)
    library = compile_c(tmp_path, "arm")
    n = model.n
    tau, M = c_function(library, "arm_tau", 3, n), c_function(library, "arm_M", 1, n * n)
    for q, qd, qdd in zip(*random_states(n, seed=5, count=30)):
        assert tau(q, qd, qdd).tobytes() == rnea(model, q, qd, qdd).tobytes()
        assert M(q).tobytes() == mass_matrix(model, q).tobytes()


def test_pairs_are_independent_operations_of_one_kind():
    kernel = kernels_of(generic_arm()).kernel("mass_matrix")
    program = with_constants(kernel.program, "k", kernel.constants)
    pairs, lane = plan_pairs(program)
    assert pairs
    above: list[set] = []
    for op, args in program.ops:
        operands = [] if op == "in" else [a for a in args[:1] if isinstance(a, int)] if op in ("cos", "sin") else args
        above.append(set().union(*({a} | above[a] for a in operands if isinstance(a, int))))
    for p, (x, y, _) in enumerate(pairs):
        assert program.ops[x][0] == program.ops[y][0] and lane[x] == (p, 0) and lane[y] == (p, 1)
        assert x not in above[y] and y not in above[x]


def test_no_pairs_where_they_do_not_pay():
    """The IRB-140's zeros leave no long isomorphic computations: its C stays scalar."""
    from irb140_dynamics.core import irb140

    kernel = kernels_of(irb140()).kernel("mass_matrix")
    program = with_constants(kernel.program, "k", kernel.constants)
    assert paired_body(program, []) is None


def test_the_tally_counts_each_candidate_as_the_whole_program_does(monkeypatch):
    """The search's count of a candidate, from the operations it touches (``_Tally``), is
    ``_cost``'s count of the whole program with it: the choices rest on it."""
    counted = []
    count_with = pairs._Tally.count_with

    def checked(tally, grown):
        count = count_with(tally, grown)
        lane = dict(tally.plan.lane)
        for p, (x, y, _) in enumerate(grown, start=len(tally.plan.pairs)):
            lane[x], lane[y] = (p, 0), (p, 1)
        assert count == pairs._cost(tally.plan, tally.plan.pairs + grown, lane)
        counted.append(count)
        return count

    monkeypatch.setattr(pairs._Tally, "count_with", checked)
    kernel = kernels_of(generic_arm()).kernel("mass_matrix")
    assert plan_pairs(with_constants(kernel.program, "k", kernel.constants))[0]
    assert len(counted) > 50
