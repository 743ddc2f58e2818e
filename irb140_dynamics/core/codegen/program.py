"""The one intermediate form of a traced algorithm: a list of single assignments.

An algorithm is traced once per model (``trace``); the traced graph is lowered here into a
``Program``: its argument groups, its operations in an order where each comes after its
operands, and its outputs. The emitters read nothing else: straight-line Python
(``python_code``), the NumPy form writing into given arrays (``array_code``) and C
(``c_code``). They write the same operations on the same operands in the same order, so
every form gives the same floating-point numbers.

An operation is ``(op, args)``:

- ``("in", (name,))``: an input, ``name`` = group and index, e.g. ``qd2``;
- ``("+" | "-" | "*" | "/", (a, b))``, ``("neg", (a,))``, ``("tanh", (a,))``;
- ``("cos" | "sin", (a, offset))``: cos or sin of input ``a`` plus the float ``offset``
  (a joint angle: theta_i = q_i + theta_offset_i, the offset less its whole quarter turns,
  which the tracer applies as a swap and signs: ``trace.quarter_turns``; offset 0.0 adds
  nothing); for a mimic joint ``a`` is the operation multiplier * q_k.

An operand is an int (the index of an earlier operation) or a float (a constant).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from irb140_dynamics.core.codegen.trace import Sym, merging, quarter_turns, trace

ANGLES = ("cos", "sin")


@dataclass(frozen=True)
class Program:
    """A traced algorithm: ``groups`` the arguments ((name, length), q first when the joints
    are angles), ``ops`` the single assignments, ``outputs`` their values (an index into
    ``ops``, or a float folded at tracing); ``matrices``: when not 0, the outputs are that
    many square matrices, row by row, one after the other (the C form returns them apart)."""

    name: str
    groups: tuple[tuple[str, int], ...]
    ops: tuple[tuple[str, tuple], ...]
    outputs: tuple
    matrices: int = 0

    def group(self, name: str) -> int:
        """The length of the argument group ``name``."""
        return dict(self.groups)[name]

    def inputs_used(self) -> set[str]:
        return {args[0] for op, args in self.ops if op == "in"}

    def uses(self) -> list[int]:
        """How many operations read each operation's value (outputs not counted)."""
        counts = [0] * len(self.ops)
        for op, args in self.ops:
            if op == "in":
                continue
            for a in args[:1] if op in ANGLES else args:
                if isinstance(a, int):
                    counts[a] += 1
        return counts


def traced(
    name: str,
    algorithm: Callable[..., Sequence],
    inputs: dict[str, int],
    angles: Sequence[float] | None = None,
    mimic_angles: Sequence[tuple] = (),
) -> Program:
    """``algorithm`` traced (see ``trace.trace``) and lowered to a Program: each operation
    once, the joint angles' cos and sin as operations on q (a mimic joint's on
    multiplier * q_k), the negations taken into the operations that read them."""
    _, outputs = trace(algorithm, inputs, angles, mimic_angles)
    groups = ((("q", len(angles)),) if angles is not None else ()) + tuple(inputs.items())
    builder = _Builder(mimic_angles)
    # c_i and s_i are the cos and sin of q_i + what is left of its offset (see trace.quarter_turns)
    rests = None if angles is None else [None if offset is None else quarter_turns(offset)[0] for offset in angles]
    index: dict[Sym, int] = {}  # each node -> its operation (a merged one's: its first's)
    ops = builder.ops
    for x, first in merging(outputs):
        if first is not x:
            index[x] = index[first]
        elif x.op == "var":
            index[x] = builder.variable(x.name, rests)
        else:  # builder.add, inline: most of a program's operations come this way
            index[x] = len(ops)
            ops.append((x.op, tuple(index[a] if type(a) is Sym else float(a) for a in x.args)))
    results = tuple(index[out] if isinstance(out, Sym) else float(out) for out in outputs)
    return Program(name, groups, *_negations_folded(builder.ops, results))


def _negations_folded(ops, outputs) -> tuple[tuple, tuple]:
    """(ops, outputs) computing the same values with each negation taken into the operations
    that read it: y - x, where x - y is computed, becomes -(x - y), and a negated value is
    added as a subtraction, multiplies a constant of the other sign, or passes its sign on
    through a product, so no operation is spent on it ("neg" stays only on an output or
    where tanh, or an angle, reads it). All exact in IEEE arithmetic (round to nearest is
    symmetric), apart from the sign of a zero."""
    new: list[tuple[str, tuple]] = []
    done: dict[tuple, int] = {}
    value: list[tuple] = []  # each old operation's (operand in new, sign)

    def emit(op: str, args: tuple) -> tuple:
        if op in "+*" and _order(args[1]) < _order(args[0]):
            args = (args[1], args[0])
        found = done.get((op, args))
        if found is not None:
            return found, 1
        if op == "-" and ("-", args[::-1]) in done:  # b - a = -(a - b)
            return done["-", args[::-1]], -1
        new.append((op, args))
        done[op, args] = len(new) - 1
        return len(new) - 1, 1

    def read(a) -> tuple:
        return value[a] if isinstance(a, int) else (a, 1)

    def whole(a) -> int | float:  # the value itself, negated where it is not
        x, sign = read(a)
        return x if sign == 1 else emit("neg", (x,))[0]

    for op, args in ops:
        if op == "in":
            value.append(emit(op, args))
        elif op in ANGLES:
            value.append(emit(op, (whole(args[0]), *args[1:])))
        elif op == "neg":
            x, sign = read(args[0])
            value.append((x, -sign))
        elif op in ("+", "-"):
            (a, sa), (b, sb) = read(args[0]), read(args[1])
            sb = sb if op == "+" else -sb  # sa a + sb b
            if sa == sb:
                x, sign = emit("+", (a, b))
                value.append((x, sign * sa))
            else:
                x, sign = emit("-", (a, b) if sa == 1 else (b, a))
                value.append((x, sign))
        elif op in ("*", "/"):
            (a, sa), (b, sb) = read(args[0]), read(args[1])
            if isinstance(b, float):  # (-y) c = y (-c); a constant's sign is its own (1)
                b, sa = b * sa, 1
            elif isinstance(a, float):
                a, sb = a * sb, 1
            x, sign = emit(op, (a, b))
            value.append((x, sign * sa * sb))
        else:  # tanh
            value.append(emit(op, (whole(args[0]),)))
    results = tuple(whole(out) if isinstance(out, int) else out for out in outputs)
    return tuple(new), results


def _order(a) -> tuple:
    """A key putting a commuting operation's operands in one order: operations first."""
    return (0, a, 0.0) if isinstance(a, int) else (1, a, math.copysign(1.0, a))


class _Builder:
    def __init__(self, mimic_angles=()):
        self.ops: list[tuple[str, tuple]] = []
        self.inputs: dict[str, int] = {}
        self.mimic_angles = mimic_angles
        self.scaled: dict[int, int] = {}  # mimic j -> the operation multiplier * q_k

    def add(self, op: str, args: tuple) -> int:
        self.ops.append((op, args))
        return len(self.ops) - 1

    def input(self, name: str) -> int:
        if name not in self.inputs:
            self.inputs[name] = self.add("in", (name,))
        return self.inputs[name]

    def variable(self, name: str, angles) -> int:
        """A traced variable: an input, or c_i / s_i, the cos / sin of joint i's angle."""
        if name[0] in "cs" and name[1:].isdigit():
            i = int(name[1:])
            return self.add("cos" if name[0] == "c" else "sin", (self.input(f"q{i}"), float(angles[i])))
        if name[:2] in ("mc", "ms", "mq") and name[2:].isdigit():
            j = int(name[2:])
            k, multiplier, offset, _ = self.mimic_angles[j]
            if j not in self.scaled:
                q = self.input(f"q{k}")
                self.scaled[j] = q if multiplier == 1.0 else self.add("*", (q, float(multiplier)))
            x = self.scaled[j]
            if name[1] == "q":  # a prismatic joint's slide, multiplier q_k + offset
                return x if offset == 0.0 else self.add("+", (x, float(offset)))
            return self.add("cos" if name[1] == "c" else "sin", (x, float(offset)))
        return self.input(name)


def with_friction(program: Program, qd_group: str, coulomb: bool) -> Program:
    """``program`` with joint friction added to its outputs (one per joint), as
    ``JointFriction.added`` adds it: out_i + (v_i qd_i [+ c_i tanh(qd_i / s)]), the
    coefficients (v, then c and s with Coulomb friction) appended to the group ``k``."""
    n = program.group(qd_group)
    k = program.group("k")
    builder = _Builder()
    builder.ops = list(program.ops)
    builder.inputs = {args[0]: i for i, (op, args) in enumerate(program.ops) if op == "in"}
    s = builder.input(f"k{k + 2 * n}") if coulomb else None
    outputs = []
    for i, out in enumerate(program.outputs):
        qd = builder.input(f"{qd_group}{i}")
        f = builder.add("*", (builder.input(f"k{k + i}"), qd))
        if coulomb:
            shape = builder.add("tanh", (builder.add("/", (qd, s)),))
            f = builder.add("+", (f, builder.add("*", (builder.input(f"k{k + n + i}"), shape))))
        outputs.append(builder.add("+", (out, f)))  # a folded output too: 0.0 + -0.0 is 0.0
    groups = tuple(
        (g, length + (2 * n + 1 if coulomb else n)) if g == "k" else (g, length) for g, length in program.groups
    )
    return Program(f"{program.name}_friction", groups, tuple(builder.ops), tuple(outputs))


def with_constants(program: Program, group: str, values: tuple) -> Program:
    """``program`` with the inputs of ``group`` replaced by ``values`` (the same floats: the
    same arithmetic), the group dropped from its arguments."""
    index: list = []
    ops: list[tuple[str, tuple]] = []
    for op, args in program.ops:
        if op == "in" and args[0].startswith(group) and args[0][len(group) :].isdigit():
            index.append(float(values[int(args[0][len(group) :])]))
            continue
        if op != "in":
            args = tuple(index[a] if isinstance(a, int) else a for a in (args[:1] if op in ANGLES else args)) + (
                args[1:] if op in ANGLES else ()
            )
        ops.append((op, args))
        index.append(len(ops) - 1)
    outputs = tuple(index[out] if isinstance(out, int) else out for out in program.outputs)
    groups = tuple((g, length) for g, length in program.groups if g != group)
    return Program(program.name, groups, tuple(ops), outputs, program.matrices)


def selected(program: Program, indices) -> Program:
    """``program`` computing only its outputs at ``indices`` (in that order): the operations
    they need, in their order (the same arithmetic)."""
    outputs = [program.outputs[i] for i in indices]
    needed, stack = set(), [out for out in outputs if isinstance(out, int)]
    while stack:
        k = stack.pop()
        if k in needed:
            continue
        needed.add(k)
        op, args = program.ops[k]
        if op != "in":
            stack += [a for a in (args[:1] if op in ANGLES else args) if isinstance(a, int)]
    order = sorted(needed)
    index = {old: new for new, old in enumerate(order)}
    ops = []
    for old in order:
        op, args = program.ops[old]
        if op != "in":
            args = tuple(
                index[a] if isinstance(a, int) and (op not in ANGLES or j == 0) else a for j, a in enumerate(args)
            )
        ops.append((op, args))
    results = tuple(index[out] if isinstance(out, int) else out for out in outputs)
    return Program(program.name, program.groups, tuple(ops), results)
