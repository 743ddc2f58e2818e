"""SymPy form: a .py that rebuilds the expressions when imported.

The module defines the symbols q1..qn, qd1..qdn, qdd1..qddn (and the parameters'), the
common subexpressions x0, x1, ... as SymPy expressions, and the quantities as Matrices:
``tau``, ``M``, ``Cqd``, ``g`` (``regressor``). Built on, e.g. ``M.diff(q2)``.
"""

from __future__ import annotations

from .printing import DESCRIPTIONS, PythonPrinter, header_lines
from .symbolic import Equations


def render(eq: Equations, reduced: dict, prefix: str, source: str) -> dict[str, str]:
    printer = PythonPrinter()
    doc = "\n".join(header_lines(eq, source))
    n = eq.n
    lines = [
        f'"""{doc}\n\nImporting this module rebuilds the expressions as SymPy Matrices.\n"""',
        "",
        "from sympy import Matrix, Rational, Symbol, cos, sin, tanh  # noqa: F401",
        "",
        f"N_JOINTS = {n}",
        f"JOINT_NAMES = {tuple(eq.joint_names)!r}",
        *(
            f"{group} = tuple(Symbol(f'{group}{{i}}', real=True) for i in range(1, {n + 1}))"
            for group in ("q", "qd", "qdd")
        ),
        *(
            f"{', '.join(f'{group}{i + 1}' for i in range(n))}{',' if n == 1 else ''} = {group}"
            for group in ("q", "qd", "qdd")
        ),
    ]
    if eq.parameters:
        lines += [f"{p.symbol.name} = Symbol({p.symbol.name!r}, real=True)  # {p.meaning}" for p in eq.parameters]
        lines.append("PARAMETERS = {" + ", ".join(f"{p.symbol.name}: {p.value!r}" for p in eq.parameters) + "}")
        lines.append('"""The model\'s values, e.g. for tau.subs(PARAMETERS)."""')
    if eq.regressor_columns:
        lines.append(f"REGRESSOR_COLUMNS = {eq.regressor_columns!r}")
    for name, (replacements, outputs) in reduced.items():
        rows, cols = (eq.shapes[name] + (1,))[:2]
        lines += ["", f"# {DESCRIPTIONS[name]}"]
        # each quantity's subexpressions under its own names: x0 of tau is not x0 of M
        lines += [f"{name}_{symbol} = {_renamed(printer.doprint(expr), name)}" for symbol, expr in replacements]
        entries = ",\n    ".join(_renamed(printer.doprint(expr), name) for expr in outputs)
        lines.append(f"{name} = Matrix({rows}, {cols}, [\n    {entries},\n])")
    return {f"{prefix}_eom_sympy.py": "\n".join(lines) + "\n"}


def _renamed(text: str, name: str) -> str:
    import re

    return re.sub(r"\bx(\d+)\b", rf"{name}_x\1", text)
