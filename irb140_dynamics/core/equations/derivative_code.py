"""The derivatives of the dynamics and M^-1 as C99 functions: the code generator's programs
(``codegen.derivative_kernels``) with the model's constants put in, the very arithmetic of
the native kernels behind ``rnea_derivatives``, ``forward_dynamics_derivatives`` and
``inverse_mass_matrix``. Matrices n x n row-major: element [i*n + j] is the derivative of
output i by input j.

    <prefix>_dtau(q, qd, qdd, dtau_dq, dtau_dqd)
    <prefix>_qdd(q, qd, tau, qdd)
    <prefix>_dqdd(q, qd, tau, dqdd_dq, dqdd_dqd)
    <prefix>_Minv(q, Minv)
"""

from __future__ import annotations

from ..codegen import sincos
from ..codegen.kernels import kernels_of
from ..codegen.layout import whole_matrix
from ..codegen.program import selected, with_constants
from ..codegen.python_code import statements

DERIVATIVE_QUANTITIES = ("dtau", "qdd", "dqdd", "Minv")

# quantity -> (kernel, its outputs written: (array, number of the kernel's outputs), description)
_WRITTEN = {
    "dtau": (
        "rnea_derivatives",
        (("dtau_dq", 2), ("dtau_dqd", 2)),
        "derivatives of the joint torques tau(q, qd, qdd) (friction included) by q and by qd",
    ),
    "qdd": ("forward_dynamics_qdd", (("qdd", 1),), "forward dynamics qdd = M(q)^-1 (tau - C qd - g - friction)"),
    "dqdd": (
        "forward_dynamics_derivatives",
        (("dqdd_dq", 2), ("dqdd_dqd", 2)),
        "derivatives of the forward dynamics qdd(q, qd, tau) by q and by qd (by tau: Minv)",
    ),
    "Minv": ("inverse_mass_matrix", (("Minv", 0),), "inverse mass matrix M(q)^-1 [1 / (kg m^2)]"),
}


def c_functions(model, what, prefix: str) -> list[tuple[str, str, list[str]]]:
    """(description, signature, body lines) of each quantity of ``what`` (of
    DERIVATIVE_QUANTITIES) for ``model``."""
    n = model.n
    functions = []
    for name in (w for w in DERIVATIVE_QUANTITIES if w in what):
        kernel_name, arrays, description = _WRITTEN[name]
        kernel = kernels_of(model).kernel(kernel_name)
        program = with_constants(kernel.program, "k", kernel.constants)
        sizes = [n if power == 1 else n * n for _, power in arrays]
        if name == "Minv":  # an upper triangle
            program = selected(program, range(len(program.outputs)))
        else:
            program = selected(program, range(sum(sizes)))
        assignments, results = statements(program)
        if name == "Minv":
            results = whole_matrix(results, n)
        groups = [group for group, _ in program.groups]
        args = [f"const double {group}[{n}]" for group in groups]
        args += [f"double {array}[{size}]" for (array, _), size in zip(arrays, sizes)]
        used = program.inputs_used()
        lines = []
        for group, length in program.groups:
            taken = [f"    const double {group}{i} = {group}[{i}];" for i in range(length) if f"{group}{i}" in used]
            lines += taken or [f"    (void){group};"]
        angles, assignments = sincos.batched(assignments)
        lines += angles
        lines += [f"    const double {var} = {expr};" for var, expr in assignments]
        start = 0
        for (array, _), size in zip(arrays, sizes):
            lines += [f"    {array}[{j}] = {results[start + j]};" for j in range(size)]
            start += size
        functions.append((description, f"void {prefix}_{name}({', '.join(args)})", lines))
    return functions
