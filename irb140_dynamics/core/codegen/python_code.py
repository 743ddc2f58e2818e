"""A Program (see ``program``) as straight-line Python, and the infix text it shares with C.

``statements`` writes each operation as an infix expression: a value used once is written
inline into its user (up to a nesting depth), any other into a variable (``t<k>``, the
joint angles' ``c<i>``, ``s<i>``). That text is valid Python and valid C: ``python_source``
wraps it into a function of floats (with ``sincos``'s sine and cosine on floats, or on
NumPy arrays to evaluate many states at once), ``c_code`` into a C function.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable

import numpy as np

from irb140_dynamics.core.codegen import sincos
from irb140_dynamics.core.codegen.program import ANGLES, Program

ANGLE_FUNCTIONS = {"cos": "cosine", "sin": "sine"}  # an angle operation's function (see sincos)
MAX_INLINE_DEPTH = 12  # of an expression written inline: deeper ones get a variable


def constant(x: float) -> str:
    """A float as exact source text (a negative one in parentheses)."""
    return f"({float(x)!r})" if x < 0 else repr(float(x))


def angle_name(program: Program, k: int) -> str:
    """The variable of the cos or sin operation k: c3 for the cos of q3 (plus its offset), a joint's;
    another one on the same q (a mimic joint's), or on an operation, gets its index too."""
    op, (a, offset) = program.ops[k]
    source_op, source_args = program.ops[a]
    if source_op == "in":
        first = next(j for j, (o, args) in enumerate(program.ops) if o == op and args[0] == a)
        if first == k:
            return f"{op[0]}{source_args[0][1:]}"
    return f"{op[0]}_{k}"


def statements(program: Program) -> tuple[list[tuple[str, str]], list[str]]:
    """(assignments (variable, expression) in order, the outputs' expressions)."""
    uses = program.uses()
    for out in program.outputs:
        if isinstance(out, int):
            uses[out] += 2  # an output is always stored in a variable
    exprs: list[str] = []  # each operation's text: its variable, or its expression inline
    depth: list[int] = []  # the nesting depth of an inline expression (0: a variable)
    lines: list[tuple[str, str]] = []
    constants: dict[float, str] = {}  # a constant's text, written once (zeros: see constant)

    def operand(a) -> tuple[str, int]:
        if type(a) is int:
            return exprs[a], depth[a]
        text = constants.get(a) if a else None
        if text is None:
            text = constant(a)
            if a:
                constants[a] = text
        return text, 0

    for k, (op, args) in enumerate(program.ops):
        if op == "in":
            exprs.append(args[0])
            depth.append(0)
            continue
        if op in ANGLES:
            q = exprs[args[0]]
            theta = q if args[1] == 0.0 else f"{q} + {args[1]!r}"
            name = angle_name(program, k)
            lines.append((name, f"{ANGLE_FUNCTIONS[op]}({theta})"))
            exprs.append(name)
            depth.append(0)
            continue
        if len(args) == 2:
            (x, dx), (y, dy) = operand(args[0]), operand(args[1])
            expr, d = f"{x} {op} {y}", 1 + (dx if dx > dy else dy)
        else:
            x, dx = operand(args[0])
            expr, d = (f"-{x}" if op == "neg" else f"tanh({x})"), 1 + dx
        if uses[k] == 1 and d < MAX_INLINE_DEPTH:
            exprs.append(f"({expr})")
            depth.append(d)
        else:
            lines.append((f"t{k}", expr))
            exprs.append(f"t{k}")
            depth.append(0)
    return lines, [operand(out)[0] for out in program.outputs]


def unpacked(program: Program) -> list[str]:
    """The lines unpacking the argument groups into variables q0, q1, ..., qd0, ... (none for
    an empty group: ``k`` of a model whose payload, last link and gravity are all zero)."""
    return [f"    {_names(group, length)} = {group}" for group, length in program.groups if length]


def python_source(program: Program, default: str | None = None) -> str:
    """``def <name>(q, qd, ...): return (outputs,)``: the program on floats. With
    ``default``, the last group (``k``) defaults to the variable of that name (see bound)."""
    lines, results = statements(program)
    lines = sincos.hoisted(lines)
    text = [f"def {program.name}({parameters(program, default)}):", *unpacked(program)]
    text += [f"    {var} = {expr}" for var, expr in lines]
    text.append(f"    return ({', '.join(results)},)")
    return "\n".join(text) + "\n"


def parameters(program: Program, default: str | None = None) -> str:
    """The groups as parameters; with ``default``, the last one defaults to that variable."""
    names = [group for group, _ in program.groups]
    if default is not None:
        names[-1] += f"={default}"
    return ", ".join(names)


BOUND = "constants"  # the variable the last group defaults to in a bound function's source


def bound(source: str, name: str, *namespaces: dict) -> list[Callable[[tuple], Callable]]:
    """``bind(constants)`` in each namespace: the function ``name`` that ``source`` defines
    (its last parameter defaulting to the variable BOUND, see python_source) with that
    parameter defaulting to ``constants``: one model's payload's numbers and gravity (see kernels).
    Each bound function is a plain function of its own, as fast to call as the code written
    out for that model. The source is compiled once."""
    wrapped = f"def bind({BOUND}):\n" + textwrap.indent(source, "    ") + f"    return {name}\n"
    code = compile(wrapped, f"<{name}>", "exec")
    binders = []
    for namespace in namespaces:
        exec(code, namespace)
        binders.append(namespace.pop("bind"))
    return binders


def compile_python(program: Program) -> tuple[str, Callable, Callable]:
    """(source, bind_scalar, bind_array): the code on floats and on NumPy arrays, each as
    ``bind(constants)`` giving the function of the groups but ``k``, which defaults to the
    constants given (see bound)."""
    source = python_source(program, default=BOUND)
    scalar_ns = {
        "cosine": sincos.cosine,
        "sine": sincos.sine,
        "sin_cos_rows": sincos.scalar_sin_cos_rows,
        "tanh": math.tanh,
    }
    array_ns = {
        "cosine": sincos.cosine_array,
        "sine": sincos.sine_array,
        "sin_cos_rows": sincos.sin_cos_rows,
        "tanh": np.tanh,
    }
    return source, *bound(source, program.name, scalar_ns, array_ns)


def _names(group: str, length: int) -> str:
    names = ", ".join(f"{group}{i}" for i in range(length))
    return names + ("," if length == 1 else "")
