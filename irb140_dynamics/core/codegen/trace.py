"""Run a scalar algorithm on symbols, once per model, recording what it computes.

The algorithms in ``algorithms`` run once on symbols instead of numbers. Every operation
on a symbol is recorded; operations on the model's constants are done right away, and
identities that are exact in floating point are folded (x*0 = 0 and x-x = 0 for finite x,
x*1, x+0, x+(-y) = x-y), and an operation recorded again on the same operands is done once
(``merging``). ``program`` lowers what is left into the intermediate form the emitters
read: no loops, no lookups, no zero terms.

What is recorded are the very floating-point operations of running the algorithm on
floats, so code emitted from it gives identical results, bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence


class Sym:
    """A traced scalar: an input, or an operation on traced scalars and constants."""

    __slots__ = ("op", "args", "name")

    def __init__(self, op: str, args: tuple = (), name: str | None = None):
        self.op, self.args, self.name = op, args, name

    # Folding: constants are Python floats, so constant-constant arithmetic never gets here.
    # Other scalar types (dual numbers) get NotImplemented and handle the operation. Each
    # operation looks at a traced operand first: the most frequent case, tested cheapest.
    def __add__(self, other):
        if other.__class__ is Sym:
            if other.op == "neg":
                return Sym("-", (self, other.args[0]))
            if self.op == "neg":
                return Sym("-", (other, self.args[0]))
            return Sym("+", (self, other))
        if not _is_const(other):
            return NotImplemented
        return self if other == 0 else Sym("+", (self, float(other)))

    def __radd__(self, other):
        return self.__add__(other)

    def __sub__(self, other):
        if other.__class__ is Sym:
            if _same(self, other):  # x - x = 0 for finite x
                return 0.0
            return self + other.args[0] if other.op == "neg" else Sym("-", (self, other))
        if not _is_const(other):
            return NotImplemented
        return self if other == 0 else Sym("-", (self, float(other)))

    def __rsub__(self, other):
        if not isinstance(other, _SCALARS):
            return NotImplemented
        if other == 0:
            return -self
        if self.op == "neg":
            return Sym("+", (float(other), self.args[0]))
        return Sym("-", (float(other), self))

    def __mul__(self, other):
        if other.__class__ is Sym:
            # (-x) y = -(x y), exactly: the negation moves out, where a sum takes it as a subtraction
            if self.op == "neg":
                if other.op == "neg":
                    return Sym("*", (self.args[0], other.args[0]))
                return -(self.args[0] * other)
            if other.op == "neg":
                return -(self * other.args[0])
            return Sym("*", (self, other))
        if not _is_const(other):
            return NotImplemented
        if other == 0:
            return 0.0
        if other == 1:
            return self
        if other == -1:
            return -self
        if self.op == "neg":  # (-x) c = x (-c)
            return Sym("*", (self.args[0], -float(other)))
        return Sym("*", (self, float(other)))

    def __rmul__(self, other):
        return self.__mul__(other)

    def __truediv__(self, other):
        if not isinstance(other, _SCALARS):
            return NotImplemented
        if _is_const(other) and other == 1:
            return self
        return Sym("/", (self, float(other) if _is_const(other) else other))

    def __rtruediv__(self, other):
        if not isinstance(other, _SCALARS):
            return NotImplemented
        _is_const(other)
        return Sym("/", (float(other), self))

    def __neg__(self):
        if self.op == "neg":
            return self.args[0]
        if self.op == "-":  # -(x - y) = y - x
            return self.args[1] - self.args[0]
        if self.op == "*" and _is_const(self.args[1]):  # -(x c) = x (-c)
            return Sym("*", (self.args[0], -self.args[1]))
        return Sym("neg", (self,))


_SCALARS = (Sym, float, int)


def tanh(x):
    """tanh of a traced scalar (recorded) or of a constant (computed)."""
    return Sym("tanh", (x,)) if isinstance(x, Sym) else math.tanh(x)


def _same(a, b, depth: int = 8) -> bool:
    """Whether a and b are the same operations on the same operands (up to ``depth`` deep):
    the same value."""
    if a is b:
        return True
    if not isinstance(a, Sym) or not isinstance(b, Sym):
        return isinstance(a, float) and isinstance(b, float) and repr(a) == repr(b)
    if a.op != b.op or a.op == "var" or depth == 0 or len(a.args) != len(b.args):
        return False
    return all(_same(x, y, depth - 1) for x, y in zip(a.args, b.args))


def _is_const(x) -> bool:
    """Whether ``x`` is a constant (a float or an int): ValueError if it is not finite."""
    if isinstance(x, (float, int)):
        if not math.isfinite(x):
            raise ValueError(f"non-finite constant {x} in a traced algorithm")
        return True
    return False


QUARTER_TURN = math.pi / 2


def quarter_turns(offset: float) -> tuple[float, int]:
    """(rest, m) with offset = m * QUARTER_TURN + rest: an offset of a whole number m of
    quarter turns (the float pi / 2 times m) is (0.0, m), any other (offset, 0). The angle
    of such a joint is then q itself, its cos and sin those of q turned m quarters (exact: a
    swap and signs), where q + offset would be rounded and need an addition."""
    m = round(offset / QUARTER_TURN)
    return (0.0, m) if m != 0 and offset == m * QUARTER_TURN else (offset, 0)


def quarter_turned(c, s, m: int) -> tuple:
    """(cos, sin) of theta + m quarter turns from (c, s) = (cos, sin) of theta."""
    for _ in range(m % 4):
        c, s = -s, c
    return c, s


def trace(
    algorithm: Callable[..., Sequence],
    inputs: dict[str, int],
    angles: Sequence[float] | None = None,
    mimic_angles: Sequence[tuple] = (),
):
    """Run ``algorithm`` on symbols: (the parameters' names, the outputs: Syms and floats).

    ``inputs`` names the argument groups and their lengths, e.g. {"qd": 6, "qdd": 6}.
    With ``angles`` (the theta offsets), a first argument ``q`` is added and the algorithm
    receives the (cos, sin) pairs of q_i + offset_i as its first argument (symbols c_i, s_i:
    those of q_i + rest_i, turned by the offset's quarter turns, see ``quarter_turns``);
    an offset None marks a prismatic joint, whose entry is (q_i,). ``mimic_angles``, each
    (k, multiplier, offset, prismatic), append the entries of joints following q_k: the
    (cos, sin) of multiplier q_k + offset (symbols mc_j, ms_j), or (multiplier q_k + offset,)
    (symbol mq_j).
    """
    args = {}
    params = []
    if angles is not None:
        params.append("q")
        args["cs"] = [
            (Sym("var", name=f"q{i}"),)
            if offset is None
            else quarter_turned(Sym("var", name=f"c{i}"), Sym("var", name=f"s{i}"), quarter_turns(offset)[1])
            for i, offset in enumerate(angles)
        ] + [
            (Sym("var", name=f"mq{j}"),) if prismatic else (Sym("var", name=f"mc{j}"), Sym("var", name=f"ms{j}"))
            for j, (_, _, _, prismatic) in enumerate(mimic_angles)
        ]
    for group, length in inputs.items():
        params.append(group)
        args[group] = [Sym("var", name=f"{group}{i}") for i in range(length)]
    return params, list(algorithm(*args.values()))


def operands_first(outputs: list) -> list[Sym]:
    """The nodes the outputs need, each after its operands (depth first, in the outputs' order)."""
    order, seen = [], set()  # a Sym hashes by identity
    for out in outputs:
        if type(out) is not Sym or out in seen:
            continue
        seen.add(out)
        stack = [(out, iter(out.args))]
        while stack:
            x, operands = stack[-1]
            for a in operands:  # resumed where it stopped: the next operand not seen yet
                if type(a) is Sym and a not in seen:
                    seen.add(a)
                    stack.append((a, iter(a.args)))
                    break
            else:
                stack.pop()
                order.append(x)
    return order


def size(outputs: list) -> int:
    """How many nodes the outputs need: ``len(operands_first(outputs))``, without the order."""
    seen: set[Sym] = set()
    stack = [out for out in outputs if type(out) is Sym]
    while stack:
        x = stack.pop()
        if type(x) is Sym and x not in seen:
            seen.add(x)
            stack.extend(x.args)
    return len(seen)


def merging(outputs: list):
    """Each operation done once: the tracer records an operation again each time the
    algorithm does it, on the same operands, or swapped (exact: IEEE + and * commute).

    Yields (node, first) for each node the outputs need, operands first (``operands_first``),
    ``first`` the first of them doing the same operation on the same operands (their firsts;
    swapped for + and *): itself, or one before it. A node that is its own first is an
    operation of the merged graph, on its operands' firsts; in this order they are the merged
    graph's nodes in its own depth-first order (a duplicate's operands are merged already)."""
    done: dict[tuple, Sym] = {}
    first_of: dict[Sym, Sym] = {}
    copysign = math.copysign
    for x in operands_first(outputs):
        op, args = x.op, x.args
        if op == "var":
            first_of[x] = x
            yield x, x
            continue
        # an operand's key: its first's identity (an int), or a constant's value and sign
        # (a tuple: -0.0 is not 0.0); those of + and * in one order: ints first, each kind sorted
        a = args[0]
        ka = id(first_of[a]) if type(a) is Sym else (float(a), copysign(1.0, a))
        if len(args) == 1:
            key = (op, ka)
        else:
            b = args[1]
            kb = id(first_of[b]) if type(b) is Sym else (float(b), copysign(1.0, b))
            if op in "+*" and (kb < ka if type(ka) is type(kb) else type(kb) is int):
                ka, kb = kb, ka
            key = (op, ka, kb)
        first = done.setdefault(key, x)
        first_of[x] = first
        yield x, first
