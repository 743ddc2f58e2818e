"""C99 form: a header and a source file, libm only, no allocation, no global state.

One function per quantity, ``<prefix>_tau(q, qd, qdd, tau)``, ``<prefix>_M(q, M)`` (row-major
n x n), ``<prefix>_Cqd(q, qd, Cqd)``, ``<prefix>_g(q, g)`` and ``<prefix>_regressor(q, qd,
qdd, Y)``; with symbolic parameters each takes ``p`` (the parameters) last.
"""

from __future__ import annotations

import math

from ..codegen import sincos
from ..codegen.pairs import paired_body
from .printing import DESCRIPTIONS, CPrinter, header_lines, used_names
from .symbolic import Equations


def render(
    eq: Equations, reduced: dict, prefix: str, source: str, bodies: dict | None = None, functions=()
) -> dict[str, str]:
    """{file name: text} of the .h and .c pair; a quantity in ``bodies`` (see traced)
    written from its program, the others from ``reduced``; then ``functions``
    ((description, signature, body lines), see derivative_code)."""
    bodies = bodies or {}
    guard = f"{prefix.upper()}_EOM_H"
    comment = _comment(header_lines(eq, source, traced=bool(bodies)))
    h = [comment, f"#ifndef {guard}", f"#define {guard}", "", f"#define {prefix.upper()}_N {eq.n}"]
    if eq.parameters:
        h.append(f"#define {prefix.upper()}_N_PARAMETERS {len(eq.parameters)}")
        values = ", ".join(repr(p.value) for p in eq.parameters)
        h.append(f"/* The model's parameter values, as an initializer: double p[] = {prefix.upper()}_PARAMETERS; */")
        h.append(f"#define {prefix.upper()}_PARAMETERS {{{values}}}")
    h += ["", "#ifdef __cplusplus", 'extern "C" {', "#endif", ""]
    c = [comment, f'#include "{prefix}_eom.h"', "", "#include <math.h>", ""]
    if bodies or functions:  # the programs' joint angles (see codegen.sincos)
        c.append(sincos.C_SOURCE)
    for name, (replacements, outputs) in reduced.items():
        signature = _signature(eq, name, prefix)
        h += [f"/* {DESCRIPTIONS[name]} */", f"{signature};", ""]
        body = _traced_body(eq, name, bodies[name]) if name in bodies else _body(eq, name, replacements, outputs)
        c += [signature, "{", *body, "}", ""]
    for description, signature, body in functions:
        h += [f"/* {description} */", f"{signature};", ""]
        c += [signature, "{", *body, "}", ""]
    h += ["#ifdef __cplusplus", "}", "#endif", "", f"#endif /* {guard} */", ""]
    return {f"{prefix}_eom.h": "\n".join(h), f"{prefix}_eom.c": "\n".join(c)}


def _comment(lines: list[str]) -> str:
    return "/*\n" + "\n".join(f" * {line}".rstrip() for line in lines) + "\n */\n"


def _signature(eq: Equations, name: str, prefix: str) -> str:
    n = eq.n
    size = math.prod(eq.shapes[name])  # the regressor's n x 13 n_links (mimic joints' links too)
    args = [f"const double {arg}[{n}]" for arg in eq.arguments[name]]
    args.append(f"double {name if name != 'regressor' else 'Y'}[{size}]")
    if eq.parameters:
        args.append(f"const double p[{len(eq.parameters)}]")
    return f"void {prefix}_{name}({', '.join(args)})"


def _body(eq: Equations, name: str, replacements, outputs) -> list[str]:
    printer = CPrinter()
    used = used_names(replacements, outputs)
    lines = []
    for arg in (*eq.arguments[name], *(("p",) if eq.parameters else ())):
        if arg == "p":
            names = [(p.symbol.name, f"p[{k}]") for k, p in enumerate(eq.parameters)]
        else:
            names = [(f"{arg}{i + 1}", f"{arg}[{i}]") for i in range(eq.n)]
        taken = [f"    const double {var} = {ref};" for var, ref in names if var in used]
        lines += taken or [f"    (void){arg};"]
    for symbol, expr in replacements:
        lines.append(f"    const double {symbol} = {printer.doprint(expr)};")
    out = name if name != "regressor" else "Y"
    lines += [f"    {out}[{k}] = {printer.doprint(expr)};" for k, expr in enumerate(outputs)]
    return lines


def _traced_body(eq: Equations, name: str, body) -> list[str]:
    lines = []
    for arg in eq.arguments[name]:
        taken = [f"    const double {var} = {arg}[{i}];" for i, var in body.inputs.get(arg, [])]
        lines += taken or [f"    (void){arg};"]
    angles, assignments = sincos.batched(body.assignments)
    lines += angles
    scalar = [f"    const double {var} = {expr};" for var, expr in assignments]
    paired = paired_body(body.program, assignments)  # operations in pairs of vectors, where they pay
    lines += ["#if defined(SINCOS_PAIRS)", *paired, "#else", *scalar, "#endif"] if paired else scalar
    out = name if name != "regressor" else "Y"
    return lines + [f"    {out}[{k}] = {expr};" for k, expr in enumerate(body.outputs)]
