"""Turn a scalar algorithm into straight-line Python for one model.

The algorithms in ``algorithms`` run once on symbols instead of numbers. Every operation
on a symbol is recorded; operations on the model's constants are done right away, and
identities that are exact in floating point are folded (x*0 = 0 for finite x, x*1, x+0,
x+(-y) = x-y), and an operation recorded again on the same operands is done once. What is left is emitted as one Python function of plain float arithmetic:
no loops, no lookups, no zero terms. The same source, compiled with NumPy's cos and sin,
evaluates many states at once when given arrays.

The generated code performs the same floating-point operations as running the algorithm
on floats, so its results are identical to it, bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

_MAX_INLINE_DEPTH = 12


class Sym:
    """A traced scalar: an input, or an operation on traced scalars and constants."""

    __slots__ = ("op", "args", "name", "uses", "index")

    def __init__(self, op: str, args: tuple = (), name: str | None = None):
        self.op, self.args, self.name = op, args, name
        self.uses = 0
        self.index = -1

    # Folding: constants are Python floats, so constant-constant arithmetic never gets here.
    # Other scalar types (dual numbers) get NotImplemented and handle the operation.
    def __add__(self, other):
        if not isinstance(other, _SCALARS):
            return NotImplemented
        if _is_const(other):
            return self if other == 0 else Sym("+", (self, float(other)))
        if other.op == "neg":
            return Sym("-", (self, other.args[0]))
        if self.op == "neg":
            return Sym("-", (other, self.args[0]))
        return Sym("+", (self, other))

    def __radd__(self, other):
        return self.__add__(other)

    def __sub__(self, other):
        if not isinstance(other, _SCALARS):
            return NotImplemented
        if _is_const(other):
            return self if other == 0 else Sym("-", (self, float(other)))
        if other.op == "neg":
            return self + other.args[0]
        return Sym("-", (self, other))

    def __rsub__(self, other):
        if not isinstance(other, _SCALARS):
            return NotImplemented
        if other == 0:
            return -self
        if self.op == "neg":
            return Sym("+", (float(other), self.args[0]))
        return Sym("-", (float(other), self))

    def __mul__(self, other):
        if not isinstance(other, _SCALARS):
            return NotImplemented
        if _is_const(other):
            if other == 0:
                return 0.0
            if other == 1:
                return self
            if other == -1:
                return -self
            if self.op == "neg":  # (-x) c = x (-c)
                return Sym("*", (self.args[0], -float(other)))
            return Sym("*", (self, float(other)))
        # (-x) y = -(x y), exactly: the negation moves out, where a sum takes it as a subtraction
        if self.op == "neg" and other.op == "neg":
            return Sym("*", (self.args[0], other.args[0]))
        if self.op == "neg":
            return -(self.args[0] * other)
        if other.op == "neg":
            return -(self * other.args[0])
        return Sym("*", (self, other))

    def __rmul__(self, other):
        return self.__mul__(other)

    def __neg__(self):
        if self.op == "neg":
            return self.args[0]
        if self.op == "-":  # -(x - y) = y - x
            return self.args[1] - self.args[0]
        if self.op == "*" and _is_const(self.args[1]):  # -(x c) = x (-c)
            return Sym("*", (self.args[0], -self.args[1]))
        return Sym("neg", (self,))


_SCALARS = (Sym, float, int)


def _is_const(x) -> bool:
    if isinstance(x, (float, int)):
        if not math.isfinite(x):
            raise ValueError(f"non-finite constant {x} in a traced algorithm")
        return True
    return False


def trace(algorithm: Callable[..., Sequence], inputs: dict[str, int], angles: Sequence[float] | None = None):
    """Run ``algorithm`` on symbols: (the parameters' names, the outputs: Syms and floats).

    ``inputs`` names the argument groups and their lengths, e.g. {"qd": 6, "qdd": 6}.
    With ``angles`` (the theta offsets), a first argument ``q`` is added and the algorithm
    receives the (cos, sin) pairs of q_i + offset_i (symbols c_i, s_i) as its first argument;
    an offset None marks a prismatic joint, whose entry is (q_i,).
    """
    args = {}
    params = []
    if angles is not None:
        params.append("q")
        args["cs"] = [
            (Sym("var", name=f"q{i}"),) if offset is None else (Sym("var", name=f"c{i}"), Sym("var", name=f"s{i}"))
            for i, offset in enumerate(angles)
        ]
    for group, length in inputs.items():
        params.append(group)
        args[group] = [Sym("var", name=f"{group}{i}") for i in range(length)]
    return params, list(algorithm(*args.values()))


def compile_kernel(
    name: str,
    algorithm: Callable[..., Sequence],
    inputs: dict[str, int],
    angles: Sequence[float] | None = None,
) -> tuple[str, Callable, Callable]:
    """Trace ``algorithm`` (see ``trace``) and compile it.

    Returns (source, scalar_fn, array_fn): array_fn evaluates the same code on NumPy arrays.
    """
    params, outputs = trace(algorithm, inputs, angles)
    outputs = merged(outputs)
    lines = [f"def {name}({', '.join(params)}):"]
    lines += input_lines(inputs, angles)
    body, results, used = _emit(outputs)
    lines += angle_lines(angles, used)
    lines += body
    lines.append(f"    return ({', '.join(results)},)")
    source = "\n".join(lines) + "\n"
    code = compile(source, f"<{name}>", "exec")
    scalar_ns = {"cos": math.cos, "sin": math.sin}
    array_ns = {"cos": np.cos, "sin": np.sin}
    exec(code, scalar_ns)
    exec(code, array_ns)
    return source, scalar_ns[name], array_ns[name]


def input_lines(inputs: dict[str, int], angles: Sequence[float] | None) -> list[str]:
    """The lines unpacking the argument groups into variables q0, q1, ..., qd0, ... (none for
    an empty group: ``k`` of a model whose payload, last link and gravity are all zero)."""
    lines = [f"    {_unpack('q', len(angles))} = q"] if angles is not None else []
    return lines + [f"    {_unpack(group, length)} = {group}" for group, length in inputs.items() if length]


def angle_lines(angles: Sequence[float] | None, used: set[str]) -> list[str]:
    """The lines computing the cosines and sines among ``used``."""
    lines = []
    for i, offset in enumerate(angles or ()):
        if offset is None:  # prismatic: q_i itself
            continue
        theta = f"q{i}" if offset == 0 else f"q{i} + {offset!r}"
        for var, fn in ((f"c{i}", "cos"), (f"s{i}", "sin")):
            if var in used:
                lines.append(f"    {var} = {fn}({theta})")
    return lines


def _unpack(group: str, length: int) -> str:
    names = ", ".join(f"{group}{i}" for i in range(length))
    return names + ("," if length == 1 else "")


def _emit(outputs: list) -> tuple[list[str], list[str], set[str]]:
    """Lines computing the live operations, the outputs' expressions, the inputs used."""
    order = operands_first(outputs)
    for k, x in enumerate(order):
        x.index = k
        for arg in x.args:
            if isinstance(arg, Sym):
                arg.uses += 1
    for out in outputs:
        if isinstance(out, Sym):
            out.uses += 2  # an output is always stored in a variable

    depth: dict[int, int] = {}
    exprs: dict[int, str] = {}
    lines = []
    for x in order:
        if x.op == "var":
            exprs[x.index] = x.name
            depth[x.index] = 0
            continue
        operands = [operand(arg, exprs) for arg in x.args]
        if x.op == "neg":
            expr = f"-{operands[0]}"
        else:
            expr = f"{operands[0]} {x.op} {operands[1]}"
        d = 1 + max((depth[a.index] for a in x.args if isinstance(a, Sym)), default=0)
        if x.uses == 1 and d < _MAX_INLINE_DEPTH:
            exprs[x.index] = f"({expr})"
            depth[x.index] = d
        else:
            lines.append(f"    t{x.index} = {expr}")
            exprs[x.index] = f"t{x.index}"
            depth[x.index] = 0
    results = [operand(out, exprs) for out in outputs]
    used = {x.name for x in order if x.op == "var"}
    for x in order:  # leave the traced graph reusable
        x.uses, x.index = 0, -1
    return lines, results, used


def operands_first(outputs: list) -> list[Sym]:
    """The nodes the outputs need, each after its operands (depth first, in the outputs' order)."""
    order, seen = [], set()
    for out in outputs:
        stack = [(out, False)]
        while stack:
            x, expanded = stack.pop()
            if not isinstance(x, Sym):
                continue
            if expanded:
                order.append(x)
            elif id(x) not in seen:
                seen.add(id(x))
                stack.append((x, True))
                stack.extend((arg, False) for arg in reversed(x.args))
    return order


def operand(x, exprs) -> str:
    if isinstance(x, Sym):
        return exprs[x.index]
    return f"({float(x)!r})" if x < 0 else repr(float(x))


def merged(outputs: list) -> list:
    """The outputs with each operation done once: the tracer records an operation again
    each time the algorithm does it, on the same operands, or swapped (exact: IEEE + and *
    commute)."""
    done: dict[tuple, Sym] = {}
    new: dict[int, Sym] = {}
    for x in operands_first(outputs):
        if x.op == "var":
            new[id(x)] = x
            continue
        args = tuple(new[id(a)] if isinstance(a, Sym) else a for a in x.args)
        keys = [("s", id(a)) if isinstance(a, Sym) else ("c", repr(float(a))) for a in args]
        key = (x.op, *(sorted(keys) if x.op in "+*" else keys))
        if key not in done:
            done[key] = Sym(x.op, args)
        new[id(x)] = done[key]
    return [new[id(out)] if isinstance(out, Sym) else out for out in outputs]
