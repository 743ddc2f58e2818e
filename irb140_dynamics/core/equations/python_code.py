"""NumPy form: a module with functions tau, M, Cqd, g (and regressor) of one state or a batch.

Each function takes arrays shaped (n,) (one state) or (N, n) (N states) and returns (n,) /
(N, n) (M: (n, n) / (N, n, n)). The straight-line code runs once on whole columns of
states, chunk by chunk so that its intermediates stay in the CPU caches.
"""

from __future__ import annotations

from ..codegen import sincos
from .printing import DESCRIPTIONS, PythonPrinter, header_lines, used_names
from .symbolic import Equations

_PRELUDE = '''
import numpy as np
from numpy import add, cos, empty, sin, tanh  # noqa: F401 (used by the generated code)
from numpy import divide as div, multiply as mul, negative as neg, subtract as sub  # noqa: F401
{sincos}
CHUNK = 4096  # states per pass


def _run(kernel, shape, *arrays):
    """kernel(columns...) -> entries, over one state or a batch of them, shaped (..., *shape)."""
    arrays = [np.asarray(a, dtype=float) for a in arrays]
    single = arrays[0].ndim == 1
    columns = [np.ascontiguousarray(np.atleast_2d(a).T) for a in arrays]
    N = columns[0].shape[1]
    out = np.empty((N, *shape))
    flat = out.reshape(N, -1)
    for start in range(0, N, CHUNK):
        part = slice(start, start + CHUNK)
        for k, entry in enumerate(kernel(*(c[:, part] for c in columns))):
            flat[part, k] = entry
    return out[0] if single else out
'''
# the joint angles' sine and cosine of the programs, the package's arithmetic (codegen.sincos)
_SINCOS = (
    "\n# sine and cosine of the joint angles: Cody-Waite reduction, fdlibm's polynomials"
    + sincos.ARRAY_SOURCE
    + "\n\nsine, cosine = sine_array, cosine_array\n"
)


def render(eq: Equations, reduced: dict, prefix: str, source: str, bodies: dict | None = None) -> dict[str, str]:
    """{file name: text} of the module; a quantity in ``bodies`` (see traced) written from
    its program, the others from ``reduced``."""
    bodies = bodies or {}
    doc = "\n".join(header_lines(eq, source, traced=bool(bodies)))
    prelude = _PRELUDE.replace("{sincos}", _SINCOS if bodies else "")
    lines = [f'"""{doc}\n\nFunctions of one state (arrays (n,)) or N states ((N, n)).\n"""', prelude]
    lines.append(f"N_JOINTS = {eq.n}")
    lines.append(f"JOINT_NAMES = {tuple(eq.joint_names)!r}")
    if eq.parameters:
        lines.append(f"PARAMETER_NAMES = {tuple(p.symbol.name for p in eq.parameters)!r}")
        lines.append(f"PARAMETERS = np.array({[p.value for p in eq.parameters]!r})  # the model's values")
    if eq.regressor_columns:
        lines.append(f"REGRESSOR_COLUMNS = {eq.regressor_columns!r}")
    for name, (replacements, outputs) in reduced.items():
        lines += ["", ""] + _function(eq, name, replacements, outputs, bodies.get(name))
    return {f"{prefix}_eom.py": "\n".join(lines) + "\n"}


def _function(eq: Equations, name: str, replacements, outputs, body=None) -> list[str]:
    printer = PythonPrinter()
    args = list(eq.arguments[name])
    shape = eq.shapes[name]  # the regressor's n x 13 n_links (mimic joints' links too)
    signature = ", ".join(args + (["p=PARAMETERS"] if eq.parameters else []))
    used = used_names(replacements, outputs)
    kernel_args = args + (["p"] if eq.parameters else [])
    lines = [f"def {name}({signature}):", f'    """{DESCRIPTIONS[name]}"""']
    if eq.parameters:
        lines.append("    p = np.asarray(p, dtype=float)")
        lines.append(
            f"    return _run(lambda {', '.join(args)}: _{name}({', '.join(args)}, p), {shape!r}, {', '.join(args)})"
        )
    else:
        lines.append(f"    return _run(_{name}, {shape!r}, {', '.join(args)})")
    lines += ["", "", f"def _{name}({', '.join(kernel_args)}):"]
    if body is not None:
        return lines[:-3] + _traced_lines(name, args, body)
    for arg in args:
        names = [f"{arg}{i + 1}" for i in range(eq.n)]
        if any(v in used for v in names):
            lines.append(f"    {', '.join(v if v in used else '_' for v in names)} = {arg}")
    for k, p in enumerate(eq.parameters):
        if p.symbol.name in used:
            lines.append(f"    {p.symbol.name} = p[{k}]")
    for symbol, expr in replacements:
        lines.append(f"    {symbol} = {printer.doprint(expr)}")
    lines.append("    return (")
    lines += [f"        {printer.doprint(expr)}," for expr in outputs]
    lines.append("    )")
    return lines


def _traced_lines(name: str, args: list[str], body) -> list[str]:
    """``_<name>``: the rows of the entries, written by ``_<name>_into`` (the code
    generator's program as NumPy ufunc calls into reused buffers)."""
    rows = len(body.constants) + len(body.written)
    lines = ["", "", f"def _{name}({', '.join(args)}):", f"    out = empty(({rows}, {args[0]}.shape[1]))"]
    lines.append(f"    _{name}_into(out, {', '.join(args)})")
    lines += [f"    out[{j}] = {value!r}" for j, value in body.constants.items()]
    ordered = body.entries != list(range(rows))
    lines.append(f"    return out[{body.entries!r}]" if ordered else "    return out")
    return [*lines, "", "", *body.into.rstrip("\n").split("\n")]
