"""A Program's operations two at a time: the C body on vectors of two doubles (SSE2, NEON).

SSE2's scalar instructions take one double each, and their two-operand form adds a copy
for most operations: the generated code is as many copies and spills as arithmetic. The
same instructions on a vector of two doubles do two operations for the price of one, each
lane the IEEE operation of the scalar code on the same operands (no contraction, no
reassociation): the results are the same bits. ``paired_body`` finds pairs of operations
of the same kind that do not depend on each other and whose operands are pairs too (the
same computation on two links' independent terms, or on two components of a vector) and
writes them as GCC's vector extensions (the type ``sincos_pair`` of ``sincos``), the
others as scalars; building a vector from two scalars, or taking a scalar out of a
vector's upper lane, costs instructions, so a pairing is kept only where it saves some
(``_cost``, a count of instructions).

The search: operations grouped by the shape of their expression a few levels deep, each
(largest first) tried with a few of its group; a pair grows down through its operands
(``_grown``) and is kept when the whole program's count falls (``_Tally``: the count kept
as pairs are added, a candidate's from the operations it touches).
"""

from __future__ import annotations

import heapq
from collections import ChainMap, Counter

from irb140_dynamics.core.codegen.program import ANGLES, Program
from irb140_dynamics.core.codegen.python_code import ANGLE_FUNCTIONS, angle_name, constant

PACKED = ("+", "-", "*", "/", "neg")  # operations a vector does lane by lane, as the scalar code
COMMUTING = ("+", "*")  # exactly, in IEEE arithmetic: their operands may swap
SHAPE_DEPTH = 3  # levels of an expression compared to group candidates
CANDIDATES = 6  # partners tried for each operation
MAX_OPS = 2000  # larger programs are written as scalars (the search: 0.05 s for the Panda's
# tau of 680 operations, about 1 s for a 7-joint chain's of 1,700 with no zero in its geometry)
# The count's weights, and when pairs are written, as measured (gcc -O2 on x86-64, a plain C
# harness, paired blocks): counting a vector built of two values, or an upper lane taken out
# for a scalar, as two instructions (a shuffle and a copy, or a load: SSE2 builds from
# registers in two steps) keeps the short runs of pairs between scalars, which are as slow
# as the scalars or slower, out; what stays are long isomorphic computations (two links' own
# wrenches, two rows of a link's inertia times a vector): tau 0.97x of its time on the
# Panda (0.95x before its links were regrouped), 0.88-0.90x and M 0.79-0.82x on random
# chains with no zero in their geometry.
BUILT = 2  # instructions counted per vector built of two values
TAKEN_OUT = 2  # per upper lane taken out for a scalar
MIN_SAVING = 0.02  # the pairs are written only when they save this share of the count


class _Plan:
    """The pairs chosen for a program: ``pairs`` [(lane 0 op, lane 1 op, swapped)], and
    ``lane`` op -> (pair, lane). ``swapped``: lane 1's operands taken in the other order."""

    def __init__(self, program: Program):
        self.program = program
        self.ops = program.ops
        n = len(self.ops)
        self.packable = [op in PACKED for op, _ in self.ops]
        self.operands = [_operands(op, args) for op, args in self.ops]
        above = [0] * n  # bit j: operation j is an operand, or an operand's operand, ...
        for k in range(n):
            m = 0
            for a in self.operands[k]:
                if type(a) is int:
                    m |= above[a] | (1 << a)
            above[k] = m
        self.above = above
        self.pairs: list[tuple[int, int, bool]] = []
        self.lane: dict[int, tuple[int, int]] = {}

    def independent(self, a: int, b: int) -> bool:
        return not (self.above[a] >> b) & 1 and not (self.above[b] >> a) & 1

    def fits(self, a, b, taken) -> bool:
        """Whether operations a and b may be one pair (neither taken)."""
        return (
            type(a) is int
            and type(b) is int
            and a != b
            and self.packable[a]
            and self.ops[a][0] == self.ops[b][0]
            and a not in self.lane
            and b not in self.lane
            and a not in taken
            and b not in taken
            and self.independent(a, b)
        )


def _operands(op: str, args: tuple) -> tuple:
    if op == "in":
        return ()
    return args[:1] if op in ANGLES else args


def _shapes(plan: _Plan) -> list:
    """Each operation's shape: its kind and its operands' shapes, SHAPE_DEPTH deep
    (a constant 'c', an input or angle 'x'; a commuting operation's operands sorted)."""
    shape = [op if p else "x" for (op, _), p in zip(plan.ops, plan.packable)]
    for _ in range(SHAPE_DEPTH):
        deeper = []
        for k, (op, _) in enumerate(plan.ops):
            if not plan.packable[k]:
                deeper.append("x")
                continue
            parts = [shape[a] if type(a) is int else "c" for a in plan.operands[k]]
            if op in COMMUTING:
                parts.sort(key=repr)
            deeper.append(hash((op, *parts)))
        shape = deeper
    return shape


def _oriented(plan: _Plan, x: int, y: int, taken: dict) -> bool:
    """Whether y's operands pair better with x's swapped (for + and *)."""
    if plan.ops[x][0] not in COMMUTING:
        return False
    ax, ay = plan.operands[x], plan.operands[y]

    def score(u, v):
        if type(u) is int and type(v) is int:
            if u != v and (plan.lane.get(u, (-1,))[0] == plan.lane.get(v, (-2,))[0] or taken.get(u) == v):
                return 3
            return 2 if plan.fits(u, v, taken) else 0
        return 1 if type(u) is not int and type(v) is not int else 0

    return score(ax[0], ay[1]) + score(ax[1], ay[0]) > score(ax[0], ay[0]) + score(ax[1], ay[1])


def _grown(plan: _Plan, a: int, b: int) -> list[tuple[int, int, bool]]:
    """The pairs (a, b) and, down through the operands, every pair of operations that fits."""
    taken: dict[int, int] = {}
    grown = []
    stack = [(a, b)]
    while stack:
        x, y = stack.pop()
        if not plan.fits(x, y, taken):
            continue
        taken[x], taken[y] = y, x
        swapped = _oriented(plan, x, y, taken)
        grown.append((x, y, swapped))
        ay = plan.operands[y][::-1] if swapped else plan.operands[y]
        stack += [(u, v) for u, v in zip(plan.operands[x], ay) if type(u) is int and type(v) is int]
    return grown


def _whole(lane: dict, u, v) -> bool:
    """Whether u and v are the lanes 0 and 1 of one pair."""
    return type(u) is int and type(v) is int and u in lane and v in lane and lane[u] == (lane[v][0], 0) != lane[v]


def _cost(plan: _Plan, pairs, lane) -> int:
    """Instructions, about: one per scalar operation or pair, one per vector built of two
    scalars (or of lanes of two other pairs), one per upper lane taken out for a scalar."""
    total = 0
    built, taken_out = set(), set()
    for k, (op, _) in enumerate(plan.ops):
        if op == "in" or op in ANGLES:
            continue
        at = lane.get(k)
        if at is None:
            total += 1
            taken_out.update(a for a in plan.operands[k] if type(a) is int and lane.get(a, (0, 0))[1] == 1)
            continue
        if at[1] == 1:
            continue
        total += 1
        x, y, swapped = pairs[at[0]]
        ay = plan.operands[y][::-1] if swapped else plan.operands[y]
        for u, v in zip(plan.operands[x], ay):
            if (type(u) is int or type(v) is int) and not _whole(lane, u, v):
                built.add((u, v))
    taken_out.update(out for out in plan.program.outputs if type(out) is int and lane.get(out, (0, 0))[1] == 1)
    return total + BUILT * len(built) + TAKEN_OUT * len(taken_out)


def _order(plan: _Plan, pairs, lane) -> list | None:
    """The operations and pairs (as ("pair", index)) in an order where each comes after
    its operands, or None when two pairs wait on each other."""
    n = len(plan.ops)
    node = [lane[k][0] + n if k in lane else k for k in range(n)]
    waiting = [0] * (n + len(pairs))
    users: list[list[int]] = [[] for _ in range(n + len(pairs))]
    for k in range(n):
        for a in {node[a] for a in plan.operands[k] if type(a) is int}:
            if a != node[k]:
                users[a].append(node[k])
                waiting[node[k]] += 1

    def first(j: int) -> int:  # the original place of an operation, or of a pair's first
        return j if j < n else min(pairs[j - n][:2])

    ready = [(first(j), j) for j in range(n + len(pairs)) if waiting[j] == 0 and (j >= n or j not in lane)]
    heapq.heapify(ready)
    order = []
    while ready:
        _, k = heapq.heappop(ready)
        order.append(k)
        for u in users[k]:
            waiting[u] -= 1
            if waiting[u] == 0:
                heapq.heappush(ready, (first(u), u))
    if len(order) != n - len(lane) + len(pairs):
        return None
    return [k if k < n else ("pair", k - n) for k in order]


def plan_pairs(program: Program) -> tuple[list, dict]:
    """(pairs, lane) chosen for ``program`` (see _Plan); none for a program above MAX_OPS,
    or when they save less than MIN_SAVING of its instructions."""
    if len(program.ops) > MAX_OPS:
        return [], {}
    plan = _Plan(program)
    shape = _shapes(plan)
    groups: dict = {}
    for k in range(len(plan.ops)):
        if plan.packable[k]:
            groups.setdefault(shape[k], []).append(k)
    tally = _Tally(plan)
    scalar = best = tally.count
    for a in sorted(range(len(plan.ops)), key=lambda k: -plan.above[k].bit_count()):  # largest first
        if not plan.packable[a] or a in plan.lane:
            continue
        group = groups[shape[a]]
        near = sorted((b for b in group if b != a and b not in plan.lane), key=lambda b: abs(b - a))
        chosen = None
        for b in near[:CANDIDATES]:
            grown = _grown(plan, a, b)
            if not grown:
                continue
            cost = tally.count_with(grown)
            if cost < best and (chosen is None or cost < chosen[0]):
                chosen = cost, grown
        if chosen is not None:
            pairs, lane = plan.pairs + chosen[1], dict(plan.lane)
            for p, (x, y, _) in enumerate(chosen[1], start=len(plan.pairs)):
                lane[x], lane[y] = (p, 0), (p, 1)
            if _order(plan, pairs, lane) is not None:
                best = chosen[0]
                tally.add(chosen[1])
    if best > (1.0 - MIN_SAVING) * scalar:
        return [], {}
    return plan.pairs, plan.lane


class _Tally:
    """``_cost`` of a plan's pairs, kept as pairs are added (``add``), and of the plan with
    more pairs (``count_with``) from the operations they touch alone: the search asks it of
    every candidate, where ``_cost`` reads the whole program each time."""

    def __init__(self, plan: _Plan):
        self.plan = plan
        counted = [op != "in" and op not in ANGLES for op, _ in plan.ops]
        self.outputs = {out for out in plan.program.outputs if type(out) is int}
        self.readers = [0] * len(plan.ops)  # operand places of each operation in scalar operations
        for k in range(len(plan.ops)):
            if counted[k]:
                for a in plan.operands[k]:
                    if type(a) is int:
                        self.readers[a] += 1
        self.built: Counter = Counter()  # the vectors built for pairs' operands (u, v)
        self.keys = 0  # how many of them are built (counted above 0)
        self.reading: dict[int, set] = {}  # operation -> the pairs whose operands it is
        self.operations = sum(counted)  # scalar operations and pairs
        self.taken = 0  # upper lanes read by a scalar operation or an output

    @property
    def count(self) -> float:
        """``_cost`` of the plan's pairs."""
        return self.operations + BUILT * self.keys + TAKEN_OUT * self.taken

    def _vectors(self, pair) -> list:
        x, y, swapped = pair
        ay = self.plan.operands[y][::-1] if swapped else self.plan.operands[y]
        return [(u, v) for u, v in zip(self.plan.operands[x], ay) if type(u) is int or type(v) is int]

    def _changes(self, grown) -> tuple[dict, Counter, dict, int, int]:
        """(the lanes grown adds, the change of ``built``, each touched operation's readers,
        the change of ``keys``, the change of ``taken``) were the pairs ``grown`` added."""
        plan, lane = self.plan, self.plan.lane
        new = {}
        for p, (x, y, _) in enumerate(grown, start=len(plan.pairs)):
            new[x], new[y] = (p, 0), (p, 1)
        both = ChainMap(new, lane)
        built: Counter = Counter()
        for pair in grown:
            for u, v in self._vectors(pair):
                if not _whole(both, u, v):
                    built[(u, v)] += 1
        for p in {p for x, y, _ in grown for k in (x, y) for p in self.reading.get(k, ())}:
            for u, v in self._vectors(plan.pairs[p]):
                if not _whole(lane, u, v) and _whole(both, u, v):
                    built[(u, v)] -= 1
        readers = {}
        for x, y, _ in grown:
            readers.setdefault(y, self.readers[y])
            for k in (x, y):
                for a in plan.operands[k]:
                    if type(a) is int:
                        readers[a] = readers.get(a, self.readers[a]) - 1
        keys = sum((self.built[key] + d > 0) - (self.built[key] > 0) for key, d in built.items())
        taken = sum(self._taken(both, a, r) - self._taken(lane, a, self.readers[a]) for a, r in readers.items())
        return new, built, readers, keys, taken

    def _taken(self, lane, a: int, readers: int) -> int:
        return int(lane.get(a, (0, 0))[1] == 1 and (readers > 0 or a in self.outputs))

    def count_with(self, grown) -> float:
        """``_cost`` of the plan with the pairs ``grown`` added."""
        *_, keys, taken = self._changes(grown)
        return self.operations - len(grown) + BUILT * (self.keys + keys) + TAKEN_OUT * (self.taken + taken)

    def add(self, grown) -> None:
        """The pairs ``grown`` added to the plan."""
        plan = self.plan
        new, built, readers, keys, taken = self._changes(grown)
        self.operations -= len(grown)
        self.keys += keys
        self.taken += taken
        self.built.update(built)
        for a, r in readers.items():
            self.readers[a] = r
        for p, pair in enumerate(grown, start=len(plan.pairs)):
            for u, v in self._vectors(pair):
                for k in (u, v):
                    if type(k) is int:
                        self.reading.setdefault(k, set()).add(p)
        plan.pairs += grown
        plan.lane.update(new)


def paired_body(program: Program, scalar_lines: list[tuple[str, str]]) -> list[str] | None:
    """The C statements of ``program`` with its pairs on vectors (``sincos_pair``, inside
    ``#if defined(SINCOS_PAIRS)``): each operation's value under the name ``statements``
    gives it (t<k>, or an angle's), so that the outputs read the same names. The joint
    angles taken from inputs are left to ``sincos.batched``; ``scalar_lines`` are the other
    assignments (the angles of a mimic joint's scaled q among them). None when no pair pays."""
    pairs, lane = plan_pairs(program)
    if not pairs:
        return None
    order = _order(_Plan(program), pairs, lane)
    ops = program.ops
    named = dict(scalar_lines)
    outputs = {out for out in program.outputs if type(out) is int}

    def name(k: int) -> str:
        op, args = ops[k]
        if op == "in":
            return args[0]
        return angle_name(program, k) if op in ANGLES else f"t{k}"

    def scalar(a) -> str:
        if type(a) is not int:
            return constant(a)
        if a in lane:
            return f"p{lane[a][0]}[{lane[a][1]}]"
        return name(a)

    def vector(u, v) -> str:
        if _whole(lane, u, v):
            return f"p{lane[u][0]}"
        return f"((sincos_pair){{{scalar(u)}, {scalar(v)}}})"

    lines = []
    for k in order:
        if type(k) is tuple:
            x, y, swapped = pairs[k[1]]
            op = ops[x][0]
            ay = _operands(*ops[y])[::-1] if swapped else _operands(*ops[y])
            operands = [vector(u, v) for u, v in zip(_operands(*ops[x]), ay)]
            expr = f"-{operands[0]}" if op == "neg" else f"{operands[0]} {op} {operands[1]}"
            lines.append(f"    const sincos_pair p{k[1]} = {expr};")
            lines += [f"    const double t{j} = p{k[1]}[{i}];" for i, j in enumerate((x, y)) if j in outputs]
            continue
        op, args = ops[k]
        if op == "in":
            continue
        if op in ANGLES:  # an angle of a mimic joint's scaled q (the others are sincos.batched's)
            if name(k) in named:
                theta = scalar(args[0]) if args[1] == 0.0 else f"{scalar(args[0])} + {args[1]!r}"
                lines.append(f"    const double {name(k)} = {ANGLE_FUNCTIONS[op]}({theta});")
            continue
        if op == "neg":
            expr = f"-{scalar(args[0])}"
        elif op == "tanh":
            expr = f"tanh({scalar(args[0])})"
        else:
            expr = f"{scalar(args[0])} {op} {scalar(args[1])}"
        lines.append(f"    const double t{k} = {expr};")
    return lines
