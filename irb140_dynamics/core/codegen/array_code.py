"""The array form of a traced kernel that writes its outputs where the caller wants them.

``codegen`` evaluates one source on floats and on NumPy arrays. On arrays, each operation
of that source allocates a fresh array for its result, and every named intermediate stays
alive until the function returns: for a kernel of a thousand operations (the regressor)
most of the time goes to the allocator and to memory that has left the CPU caches. This
form runs the same operations on the same operands (so its floats are identical), as one
NumPy ufunc call each with an ``out`` argument:

- intermediates go to a few preallocated buffers, one freed as soon as its value's last
  user has run and taken by the next result (often in place), so that the working set of
  a chunk of states stays in the caches;
- the last operation of each output writes straight into the caller's array ``out[j]``;
- what depends only on the scalar arguments (the payload's numbers and gravity ``k``) is computed
  once on floats;
- an operation the tracer recorded more than once (on the same operands, or on swapped
  ones for + and *, which commute exactly) is done once;
- outputs folded to constants are not written: ``written`` lists the others.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from irb140_dynamics.core.codegen import sincos
from irb140_dynamics.core.codegen.program import ANGLES, Program
from irb140_dynamics.core.codegen.python_code import (
    ANGLE_FUNCTIONS,
    BOUND,
    angle_name,
    bound,
    constant,
    parameters,
    unpacked,
)

_UFUNCS = {"*": "mul", "+": "add", "-": "sub", "/": "div", "neg": "neg", "tanh": "tanh"}
_NAMESPACE = {
    "cosine": sincos.cosine_array,
    "sine": sincos.sine_array,
    "sin_cos_rows": sincos.sin_cos_rows,
    "mul": np.multiply,
    "add": np.add,
    "sub": np.subtract,
    "div": np.divide,
    "neg": np.negative,
    "tanh": np.tanh,
    "empty": np.empty,
}


def compile_into(program: Program, scalars: Sequence[str] = ()) -> tuple[str, Callable, list[int]]:
    """The writing array form of ``program``: (source, bind, written).

    ``bind(constants)`` gives ``fn(out, *groups)`` with the last group (``k``) defaulting to
    ``constants`` (see python_code.bound). ``fn`` takes ``out``, a sequence with a writable
    (N,) array at each index in ``written`` (the others, folded to constants, are not
    touched), and the argument groups as arrays of shape (length, N) (the groups named in
    ``scalars`` as floats).
    """
    source, written = into_source(program, scalars, default=BOUND)
    (bind,) = bound(source, f"{program.name}_into", dict(_NAMESPACE))
    return source, bind, written


def into_source(program: Program, scalars: Sequence[str] = (), default: str | None = None) -> tuple[str, list[int]]:
    """(the source of ``<name>_into``, see compile_into; the outputs it writes). Its names:
    cosine, sine, sin_cos_rows (``sincos``'s, on arrays), tanh, mul, add, sub, div, neg
    (NumPy's ufuncs) and empty (np.empty). With ``default``, the last group defaults to the
    variable of that name."""
    scalar_vars = {f"{group}{i}" for group in scalars for i in range(program.group(group))}
    body, first_array, registers = _emit_into(program, scalar_vars)
    written = [j for j, out in enumerate(program.outputs) if isinstance(out, int)]
    lines = [f"def {program.name}_into(out, {parameters(program, default)}):"]
    lines += unpacked(program)
    lines += [f"    o{j} = out[{j}]" for j in written]
    if registers:
        lines.append(f"    {''.join(f'r{i}, ' for i in range(registers))}= empty(({registers}, len({first_array})))")
    lines += body
    return "\n".join(lines) + "\n", written


def _emit_into(program: Program, scalar_vars: set[str]):
    """(body lines, an array input's name, buffers needed)."""
    ops, outputs = program.ops, program.outputs
    scalar = set()  # indices of the operations that depend on scalar inputs only
    last_use = {}
    for k, (op, args) in enumerate(ops):
        operands = () if op == "in" else [a for a in (args[:1] if op in ANGLES else args) if isinstance(a, int)]
        if (args[0] in scalar_vars) if op == "in" else all(a in scalar for a in operands):
            scalar.add(k)
        for a in operands:
            last_use[a] = k
    destination = {}  # an output's operation -> the output it is computed into
    for j, out in enumerate(outputs):
        if isinstance(out, int) and ops[out][0] not in ("in", *ANGLES) and out not in scalar:
            destination.setdefault(out, f"o{j}")

    names: dict[int, str] = {}
    lines: list[str] = []
    # the joint angles (those of an input) at once: one sin_cos_rows call on all their thetas
    angles = [
        (k, op, _theta(ops[args[0]][1][0], args[1]))
        for k, (op, args) in enumerate(ops)
        if op in ANGLES and ops[args[0]][0] == "in"
    ]
    thetas = {theta: i for i, theta in enumerate(dict.fromkeys(theta for k, op, theta in angles))}
    for k, op, theta in angles:
        names[k] = f"angle_rows[{thetas[theta] + (len(thetas) if op == 'cos' else 0)}]"
    if thetas:
        lines.append(f"    angle_rows = sin_cos_rows(({', '.join(thetas)},))")
    buffers: set[str] = set()
    free: list[str] = []  # buffers whose values are dead, the most recently freed last
    for k, (op, args) in enumerate(ops):
        if op == "in":
            names[k] = args[0]
            continue
        if op in ANGLES:  # an array of its own, computed as the Python form does
            if k not in names:  # a mimic joint's, of a multiple of an input
                names[k] = angle_name(program, k)
                lines.append(f"    {names[k]} = {ANGLE_FUNCTIONS[op]}({_theta(names[args[0]], args[1])})")
            continue
        operands = [names[a] if isinstance(a, int) else constant(a) for a in args]
        if k in scalar:
            expr = (
                f"{op}({operands[0]})"
                if op == "tanh"
                else f"-{operands[0]}"
                if op == "neg"
                else f"{operands[0]} {op} {operands[1]}"
            )
            names[k] = f"t{k}"
            lines.append(f"    t{k} = {expr}")
            continue
        for a in {a for a in args if isinstance(a, int)}:
            name = names[a]
            if last_use[a] == k and name in buffers:
                free.append(name)
        if k in destination:
            target = destination[k]
        elif free:
            target = free.pop()
        else:
            target = f"r{len(buffers)}"
            buffers.add(target)
        lines.append(f"    {_UFUNCS[op]}({', '.join(operands)}, {target})")
        names[k] = target
    for j, out in enumerate(outputs):
        if isinstance(out, int) and destination.get(out) != f"o{j}":
            lines.append(f"    o{j}[...] = {names[out]}")
    first_array = next((args[0] for op, args in ops if op == "in" and args[0] not in scalar_vars), None)
    return lines, first_array, len(buffers)


def _theta(q: str, offset: float) -> str:
    return q if offset == 0.0 else f"{q} + {offset!r}"
