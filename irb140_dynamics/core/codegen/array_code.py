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
- what depends only on the scalar arguments (the payload and gravity ``k``) is computed
  once on floats;
- an operation the tracer recorded more than once (on the same operands, or on swapped
  ones for + and *, which commute exactly) is done once;
- outputs folded to constants are not written: ``written`` lists the others.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from irb140_dynamics.core.codegen.trace import Sym, angle_lines, input_lines, merged, operand, operands_first, trace

_UFUNCS = {"*": "mul", "+": "add", "-": "sub"}
_NAMESPACE = {
    "cos": np.cos,
    "sin": np.sin,
    "mul": np.multiply,
    "add": np.add,
    "sub": np.subtract,
    "neg": np.negative,
    "empty": np.empty,
}


def compile_into(
    name: str,
    algorithm: Callable[..., Sequence],
    inputs: dict[str, int],
    angles: Sequence[float] | None = None,
    scalars: Sequence[str] = (),
) -> tuple[str, Callable, list[int]]:
    """Trace ``algorithm`` like ``codegen.compile_kernel`` and compile its writing array form.

    Returns (source, fn, written): ``fn(out, *groups)`` takes ``out``, a sequence with a
    writable (N,) array at each index in ``written`` (the others are not touched), and the
    input groups as arrays of shape (length, N) (the groups named in ``scalars`` as floats).
    """
    params, outputs = trace(algorithm, inputs, angles)
    scalar_vars = {f"{group}{i}" for group in scalars for i in range(inputs[group])}
    body, used, first_array, registers = _emit_into(outputs, scalar_vars)
    written = [j for j, out in enumerate(outputs) if isinstance(out, Sym)]
    lines = [f"def {name}_into({', '.join(['out', *params])}):"]
    lines += input_lines(inputs, angles)
    lines += angle_lines(angles, used)
    lines += [f"    o{j} = out[{j}]" for j in written]
    if registers:
        lines.append(f"    {''.join(f'r{i}, ' for i in range(registers))}= empty(({registers}, len({first_array})))")
    lines += body
    source = "\n".join(lines) + "\n"
    namespace = dict(_NAMESPACE)
    exec(compile(source, f"<{name}_into>", "exec"), namespace)
    return source, namespace[f"{name}_into"], written


def _emit_into(outputs: list, scalar_vars: set[str]):
    """(body lines, the input variables used, an array input's name, buffers needed)."""
    outputs = merged(outputs)
    order = operands_first(outputs)
    scalar = set()  # ids of the nodes that depend on scalar inputs only
    last_use = {}
    for k, x in enumerate(order):
        if (x.name in scalar_vars) if x.op == "var" else all(id(a) in scalar for a in x.args if isinstance(a, Sym)):
            scalar.add(id(x))
        for a in x.args:
            if isinstance(a, Sym):
                last_use[id(a)] = k
    destination = {}  # an output's node -> the output it is computed into
    for j, out in enumerate(outputs):
        if isinstance(out, Sym) and out.op != "var" and id(out) not in scalar:
            destination.setdefault(id(out), f"o{j}")

    names: dict[int, str] = {}
    lines: list[str] = []
    buffers: set[str] = set()
    free: list[str] = []  # buffers whose values are dead, the most recently freed last
    for k, x in enumerate(order):
        if x.op == "var":
            names[id(x)] = x.name
            continue
        operands = [names[id(a)] if isinstance(a, Sym) else operand(a, None) for a in x.args]
        if id(x) in scalar:
            expr = f"-{operands[0]}" if x.op == "neg" else f"{operands[0]} {x.op} {operands[1]}"
            names[id(x)] = f"t{k}"
            lines.append(f"    t{k} = {expr}")
            continue
        for a in {id(a): a for a in x.args if isinstance(a, Sym)}.values():
            name = names[id(a)]
            if last_use[id(a)] == k and name in buffers:
                free.append(name)
        if id(x) in destination:
            target = destination[id(x)]
        elif free:
            target = free.pop()
        else:
            target = f"r{len(buffers)}"
            buffers.add(target)
        call = "neg" if x.op == "neg" else _UFUNCS[x.op]
        lines.append(f"    {call}({', '.join(operands)}, {target})")
        names[id(x)] = target
    for j, out in enumerate(outputs):
        if isinstance(out, Sym) and destination.get(id(out)) != f"o{j}":
            lines.append(f"    o{j}[...] = {names[id(out)]}")
    used = {x.name for x in order if x.op == "var"}
    first_array = next((x.name for x in order if x.op == "var" and x.name not in scalar_vars), None)
    return lines, used, first_array, len(buffers)
