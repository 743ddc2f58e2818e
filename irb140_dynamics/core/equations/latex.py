"""LaTeX form: a document (article, amsmath) with the model's symbols, M, C qd and g per entry.

With the model's numbers, each entry is written out as a polynomial in the sines and
cosines of the joint angles, those of joints about parallel axes summed (see
``trig_series`` and ``trig_products``), numbers to 6 significant digits, when that stays
short (``MAX_TERMS`` per entry on average); otherwise, and with symbolic parameters, the
common subexpressions x_k are defined first and the entries written with them.
"""

from __future__ import annotations

import sympy as sp

from ..algorithms import recursions as algorithms
from . import trig_products as tp
from . import trig_series as ts
from .printing import header_lines
from .symbolic import Equations, links_of

MAX_TERMS = 150  # sines and cosines per entry on average, for the series form
TITLES = {
    "M": "The mass matrix $M(q)$",
    "Cqd": r"Coriolis and centrifugal torques $C(q,\dot q)\,\dot q$",
    "g": "Gravity torques $g(q)$",
    "tau": r"Joint torques $\tau$",
    "regressor": "The regressor $Y$",
}
SYMBOL = {"M": "M", "Cqd": r"(C\dot q)", "g": "g", "tau": r"\tau", "regressor": "Y"}
TERMS_PER_LINE = 3


def series(model, names) -> dict[str, list]:
    """The quantities among M, Cqd, g as Series entries (row-major), those that stay short
    (none for an arm with a prismatic joint)."""
    n = model.n
    links, _, _ = links_of(model, False)
    if any(getattr(link, "prismatic", False) for link in links):
        return {}  # a slide enters as a polynomial, not a series: the subexpression form
    cs = [ts.angle(i, n, link.theta_offset) for i, link in enumerate(links)]
    zeros = [0.0] * n
    out = {}
    if "g" in names:
        out["g"] = list(algorithms.rnea(links, cs, zeros, zeros, model.gravity))
    if "M" in names or "Cqd" in names:
        M = algorithms.crba(links, cs)
        out["M"] = [M[i][j] for i in range(n) for j in range(n)]
        if "Cqd" in names and _count(out["M"]) <= MAX_TERMS * n * n:
            qd = [ts.variable(j, n) for j in range(n)]
            out["Cqd"] = list(algorithms.rnea(links, cs, qd, zeros, (0.0, 0.0, 0.0)))
    return {k: v for k, v in out.items() if k in names and _count(v) <= MAX_TERMS * len(v)}


def _count(entries) -> int:
    return sum(len(x.terms) for x in entries if isinstance(x, ts.Series)) // 2  # exp(+-i k q): one sine or cosine


def render(eq: Equations, reduced: dict, prefix: str, source: str, expanded: dict) -> dict[str, str]:
    lines = [
        r"\documentclass[10pt]{article}",
        r"\usepackage[T1]{fontenc}",
        r"\usepackage{amsmath}",
        r"\allowdisplaybreaks",
        r"\setlength{\textwidth}{16cm}\setlength{\oddsidemargin}{0cm}",
        r"\begin{document}",
        rf"\section*{{Equations of motion: {_text(source)}}}",
        r"\[ M(q)\,\ddot q + C(q,\dot q)\,\dot q + g(q) + \tau_f(\dot q) = \tau \]",
        "",
        r"\begin{verbatim}",
        *header_lines(eq, source),
        r"\end{verbatim}",
        "",
        r"$q_i$, $\dot q_i$, $\ddot q_i$: position, velocity and acceleration of joint $i$ "
        r"(order above). "
        r"$\tau_{f,i} = f_{v,i}\,\dot q_i + f_{c,i} \tanh(\dot q_i / v_s)$ is the joint friction.",
    ]
    runs = tp.angle_runs(list(expanded.values()), eq.n) if expanded else []
    if expanded:
        lines.append(" " + _notation(runs, eq.n))
        lines.append(r" Numbers rounded to 6 significant digits; the C, Python and SymPy forms carry them in full.")
    for name in ("M", "Cqd", "g", "tau", "regressor"):
        if name not in reduced:
            continue
        lines += ["", rf"\subsection*{{{TITLES[name]}}}"]
        if name in expanded:
            lines += _series_entries(eq, name, expanded[name], runs)
        else:
            lines += _reduced_entries(eq, name, *reduced[name])
    lines += ["", r"\end{document}", ""]
    return {f"{prefix}_eom.tex": "\n".join(lines)}


def _text(s: str) -> str:
    for a, b in (
        ("\\", r"\textbackslash{}"),
        ("_", r"\_"),
        ("&", r"\&"),
        ("%", r"\%"),
        ("#", r"\#"),
        ("$", r"\$"),
        ("{", r"\{"),
        ("}", r"\}"),
        ("~", r"\~{}"),
        ("^", r"\^{}"),
    ):
        s = s.replace(a, b)
    return s


def _index(eq: Equations, name: str, k: int) -> str:
    shape = eq.shapes[name]
    return f"{k + 1}" if len(shape) == 1 else f"{k // shape[1] + 1}{k % shape[1] + 1}"


def _entries(eq, name):
    """The entries to print: all, or the upper triangle of M (symmetric)."""
    n = eq.n
    count = len(eq.quantities[name])
    return [k for k in range(count) if name != "M" or k // n <= k % n]


def _series_entries(eq: Equations, name: str, entries, runs) -> list[str]:
    numbers = [abs(c) for x in entries if isinstance(x, ts.Series) for c in x.terms.values()]
    numbers += [abs(x) for x in entries if not isinstance(x, ts.Series)]
    tolerance = 1e-10 * max(numbers, default=0.0)
    labels = [_label(joints, eq.n) for joints in tp.angle_sums(runs)]
    lines = [r"\begin{align*}"]
    for k in _entries(eq, name):
        form = tp.products(entries[k], runs, tolerance)
        lines.append(rf"{SYMBOL[name]}_{{{_index(eq, name, k)}}} &= {_form_text(eq.n, form, labels)} \\")
    if name == "M":
        lines.append(r"M_{ji} &= M_{ij} \\")
    lines[-1] = lines[-1].removesuffix(r" \\")
    return lines + [r"\end{align*}"]


def _label(joints, n: int) -> str:
    return ("," if n >= 10 else "").join(str(j + 1) for j in joints)


def _form_text(n: int, form: dict, labels: list[str]) -> str:
    pieces = []
    for v, poly in form.items():
        parts = [f"{_number(c)} {_monomial(m, labels)}".rstrip() for m, c in poly.items()]
        chunks = [" ".join(parts[i : i + TERMS_PER_LINE]) for i in range(0, len(parts), TERMS_PER_LINE)]
        body = r" \\ &\qquad ".join(chunks)
        if not v:
            pieces.append(body)
        else:
            pieces.append(rf"+ {_velocities(n, v)} \big( {body.removeprefix('+ ')} \big)")
    text = r" \\ &\quad ".join(pieces)
    return text.removeprefix("+ ") or "0"


def _monomial(monomial, labels) -> str:
    factors = []
    for (a, b), label in zip(monomial, labels):
        for letter, power in (("c", a), ("s", b)):
            if power:
                factors.append(f"{letter}_{{{label}}}" + (f"^{{{power}}}" if power > 1 else ""))
    return " ".join(factors)


def _notation(runs, n: int) -> str:
    text = r"$c_{i} = \cos q_i$, $s_{i} = \sin q_i$"
    for joints in tp.angle_sums(runs):
        if len(joints) > 1:
            angle = " + ".join(f"q_{{{j + 1}}}" for j in joints)
            label = _label(joints, n)
            text += rf", $c_{{{label}}} = \cos({angle})$, $s_{{{label}}} = \sin({angle})$"
    return text + "."


def _number(x: float) -> str:
    mantissa, _, exponent = f"{abs(x):.6g}".partition("e")
    text = mantissa if not exponent else rf"{mantissa} \times 10^{{{int(exponent)}}}"
    return ("- " if x < 0 else "+ ") + text


def _velocities(n: int, v) -> str:
    names = [rf"\dot q_{{{j + 1}}}" if j < n else rf"\ddot q_{{{j - n + 1}}}" for j in v]
    out, i = [], 0
    while i < len(names):
        power = names.count(names[i])
        out.append(names[i] + (f"^{{{power}}}" if power > 1 else ""))
        i += power
    return " ".join(out)


def _reduced_entries(eq: Equations, name: str, replacements, outputs) -> list[str]:
    names = {s: _symbol_latex(s.name) for s in (*eq.q, *eq.qd, *eq.qdd, *(p.symbol for p in eq.parameters))}
    names.update({s: f"x_{{{s.name[1:]}}}" for s, _ in replacements})

    def tex(expr):
        rounded = expr.xreplace({f: sp.Float(f, 6) for f in expr.atoms(sp.Float)})
        return sp.latex(rounded, symbol_names=names, full_prec=False)

    lines = [r"\begin{align*}"]
    lines += [rf"{names[s]} &= {tex(e)} \\" for s, e in replacements]
    lines += [
        rf"{SYMBOL[name]}_{{{_index(eq, name, k)}}} &= {tex(sp.sympify(outputs[k]))} \\" for k in _entries(eq, name)
    ]
    if name == "M":
        lines.append(r"M_{ji} &= M_{ij} \\")
    lines[-1] = lines[-1].removesuffix(r" \\")
    return lines + [r"\end{align*}"]


def _symbol_latex(name: str) -> str:
    for prefix, tex in (("qdd", r"\ddot q"), ("qd", r"\dot q"), ("q", "q")):
        if name.startswith(prefix) and name[len(prefix) :].isdigit():
            return f"{tex}_{{{name[len(prefix) :]}}}"
    head = name.rstrip("0123456789P")
    return f"{head}_{{{name[len(head) :]}}}"
