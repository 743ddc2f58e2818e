"""The numeric equations' C and Python bodies from the code generator's programs.

tau, M, Cqd and g of a model with numbers (not symbolic parameters) are written from the
programs the kernels are compiled from (``codegen.program``), with the payload, gravity
and friction constants put in: the C that ``equations`` writes, the C a node calls and
the Python form do the same arithmetic. The regressor and symbolic parameters are written
from the SymPy derivation (``symbolic``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ..codegen.array_code import into_source
from ..codegen.kernels import kernels_of
from ..codegen.layout import upper_to_full, whole_matrix
from ..codegen.program import Program, with_constants
from ..codegen.python_code import statements
from ..codegen.recipes import WITH_FRICTION

KERNEL_OF = {"tau": WITH_FRICTION, "M": "mass_matrix", "Cqd": "coriolis", "g": "gravity_torques"}


@dataclass(frozen=True)
class Body:
    """A quantity as straight-line code: the inputs it reads by group ({"q": [(0, "q0"),
    ...]}), its assignments (variable, expression) and its entries' expressions; and as
    NumPy code writing into given rows (``into``: the source of ``_<name>_into(out, ...)``,
    see codegen.array_code), with the rows it writes (``written``), the constant ones
    ({row: value}) and the entries' rows in order (``entries``: M whole from its upper
    triangle)."""

    inputs: dict[str, list[tuple[int, str]]]
    assignments: list[tuple[str, str]]
    outputs: list[str]
    into: str
    written: list[int]
    constants: dict[int, float]
    entries: list[int]
    program: Program  # the kernel's, k's numbers put in (the C writer pairs its operations)


def traced_bodies(model, names) -> dict[str, Body]:
    """The Body of each quantity of ``names`` that a program gives (see KERNEL_OF)."""
    kernels = kernels_of(model)
    bodies = {}
    for name in names:
        if name not in KERNEL_OF:
            continue
        kernel = kernels.kernel(KERNEL_OF[name])
        program = with_constants(kernel.program, "k", kernel.constants)
        assignments, outputs = statements(program)
        into, written = into_source(replace(program, name=f"_{name}"))
        constants = {j: out for j, out in enumerate(program.outputs) if not isinstance(out, int)}
        entries = list(range(len(outputs)))
        if name == "M":
            outputs = whole_matrix(outputs, model.n)
            entries = upper_to_full(model.n).ravel().tolist()
        used = program.inputs_used()
        inputs = {
            group: [(i, f"{group}{i}") for i in range(length) if f"{group}{i}" in used]
            for group, length in program.groups
        }
        bodies[name] = Body(inputs, assignments, outputs, into, written, constants, entries, program)
    return bodies
