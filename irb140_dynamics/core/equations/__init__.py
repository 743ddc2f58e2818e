"""The equations of motion in closed form: LaTeX, SymPy, C99 and NumPy Python; their
derivatives and M^-1 in C99 (``derivative_code``).

The core's own scalar recursions (``algorithms``) run on SymPy symbols (``symbolic``), the
common subexpressions are shared, and one emitter per form writes the files. The C and
Python forms of a model with numbers write tau, M, Cqd and g from the code generator's
programs instead (``traced``): the same arithmetic as the kernels the package compiles.
Imports the core (algorithms, codegen, regressor, rigid_body) and SymPy; nothing of ROS.

    files = generate(model, ("c",), prefix="irb140")      # {file name: text}
"""

from __future__ import annotations

from collections.abc import Callable

from . import c_code, derivative_code, latex, python_code, sympy_code
from .printing import reduced_quantities
from .symbolic import DEFAULT_QUANTITIES, Equations, derive
from .symbolic import QUANTITIES as SYMBOLIC_QUANTITIES
from .traced import KERNEL_OF, traced_bodies

FORMS = ("latex", "sympy", "c", "python")
_TRACED_EMITTERS = {"c": c_code.render, "python": python_code.render}  # numbers: the programs' bodies
FILE_ENDINGS = {"latex": ("_eom.tex",), "sympy": ("_eom_sympy.py",), "c": ("_eom.h", "_eom.c"), "python": ("_eom.py",)}
QUANTITIES = SYMBOLIC_QUANTITIES + derivative_code.DERIVATIVE_QUANTITIES

__all__ = ["DEFAULT_QUANTITIES", "Equations", "FORMS", "QUANTITIES", "derive", "file_names", "generate"]


def file_names(forms, prefix: str) -> list[str]:
    """The names of the files ``generate`` writes for ``forms``, known before the work."""
    return [prefix + ending for form in forms for ending in FILE_ENDINGS[form]]


def generate(
    model,
    forms=("c",),
    what=DEFAULT_QUANTITIES,
    symbolic: bool = False,
    prefix: str = "robot",
    source: str = "a robot arm",
    progress: Callable[[str], None] | None = None,
) -> dict[str, str]:
    """The files of the ``forms`` (of FORMS) for ``model``: {file name: text}. Same input,
    same bytes. ``progress(stage)`` is told what is being done."""
    unknown = [form for form in forms if form not in FORMS]
    if unknown:
        raise ValueError(f"unknown form {unknown[0]!r}: choose from {', '.join(FORMS)}")
    if not prefix.isidentifier() or not prefix.isascii():
        raise ValueError(f"prefix {prefix!r} is not a C identifier")
    progress = progress or (lambda stage: None)
    derivatives = [w for w in what if w in derivative_code.DERIVATIVE_QUANTITIES]
    if derivatives and (symbolic or any(form != "c" for form in forms)):
        raise ValueError(f"{derivatives[0]}: the derivatives are written in the C form of a model with numbers")
    what = tuple(w for w in what if w not in derivative_code.DERIVATIVE_QUANTITIES)
    # the C and Python forms of a model with numbers write tau, M, Cqd and g from the code
    # generator's programs (traced): SymPy derives only what another form or quantity reads
    programs_only = not symbolic and all(form in _TRACED_EMITTERS for form in forms)
    equations = derive(model, what, symbolic, progress, frozenset(KERNEL_OF) if programs_only else frozenset())
    if any(equations.quantities.values()):
        progress("common subexpressions")
    reduced = reduced_quantities(equations)
    files = {}
    for form in forms:
        progress(f"writing the {form} form")
        if form == "latex":
            expanded = {} if symbolic else latex.series(model, set(reduced) & {"M", "Cqd", "g"})
            files.update(latex.render(equations, reduced, prefix, source, expanded))
        elif form == "sympy":
            files.update(sympy_code.render(equations, reduced, prefix, source))
        else:
            bodies = {} if symbolic else traced_bodies(model, reduced)
            if form == "c" and derivatives:
                progress("the derivatives")
                functions = derivative_code.c_functions(model, derivatives, prefix)
                files.update(c_code.render(equations, reduced, prefix, source, bodies, functions))
            else:
                files.update(_TRACED_EMITTERS[form](equations, reduced, prefix, source, bodies))
    return files
