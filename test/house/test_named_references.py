"""Every module, class or function of the package that a docstring, comment or doc names
exists.

What counts as a reference (anywhere in the text of the package's, the tests' and the
benchmarks' Python files, the docs, the README and .importlinter):

- a dotted name that starts with the package: the package, a module, or a name in one;
- a dotted name that starts with one of the package's sub-packages and goes on at least one
  name deeper (``core.codegen.kernels``, ``identification.base.BaseParameters``), unless a
  ``/`` or a file suffix follows it (``sim.md`` is a file);
- the path of a Python file with at least one folder in it, ``nodes/id_node/node.py``,
  found from the repository's root, the package's folder or the citing file's folder
  (no wildcards, no absolute paths).

A dotted name resolves when its longest prefix that is a module of the package (a .py file
or a folder) is followed by names that module defines at its top level (def, class,
assignment, import), and, past a class, names that class's body defines.
"""

import ast
import io
import re
import tokenize
from functools import cache
from pathlib import Path

from ..support.paths import ROOT

PACKAGE = "irb140_dynamics"
SUBPACKAGES = sorted(p.name for p in (ROOT / PACKAGE).iterdir() if (p / "__init__.py").is_file())
IDENTIFIER = r"[A-Za-z_][A-Za-z0-9_]*"
FULL_NAME = re.compile(rf"(?<![\w.]){PACKAGE}(?:\.{IDENTIFIER})+")
SHORT_NAME = re.compile(rf"(?<![\w./\-]){'(?:' + '|'.join(SUBPACKAGES) + ')'}(?:\.{IDENTIFIER})+(?![\w/])")
PY_PATH = re.compile(r"(?<![\w./*~\-])(?:[\w\-]+/)+[\w\-]+\.py\b")
FILE_SUFFIX = re.compile(r"\.(md|py|yaml|yml|txt|urdf|xml|json|csv|launch|png|mcap|db3|toml|sh)$")


def cited_files():
    for folder in (PACKAGE, "test", "bench"):
        yield from sorted((ROOT / folder).rglob("*.py"))
    yield from sorted((ROOT / "docs").glob("*.md"))
    yield ROOT / "README.md"
    yield ROOT / ".importlinter"


@cache
def module_names(path: Path) -> dict[str, set[str] | None]:
    """Top-level names a module defines -> the names its class defines (None: not a class)."""
    names: dict[str, set[str] | None] = {}
    tree = ast.parse(path.read_text())
    pending = list(tree.body)
    while pending:
        node = pending.pop()
        if isinstance(node, ast.ClassDef):
            names[node.name] = {n for child in node.body for n in _defined(child)}
        else:
            for name in _defined(node):
                names.setdefault(name, None)
            if isinstance(node, (ast.If, ast.Try, ast.With)):
                pending.extend(node.body + getattr(node, "orelse", []) + getattr(node, "finalbody", []))
                for handler in getattr(node, "handlers", []):
                    pending.extend(handler.body)
    return names


def _defined(node) -> list[str]:
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return [node.name]
    if isinstance(node, (ast.Import, ast.ImportFrom)):
        return [(alias.asname or alias.name).partition(".")[0] for alias in node.names]
    targets = []
    if isinstance(node, ast.Assign):
        targets = node.targets
    elif isinstance(node, (ast.AnnAssign, ast.AugAssign)):
        targets = [node.target]
    names = []
    for target in targets:
        for element in ast.walk(target):
            if isinstance(element, ast.Name):
                names.append(element.id)
    return names


def resolves(dotted: str) -> bool:
    """Whether a dotted name from the package down names a module of it or something in one."""
    parts = dotted.split(".")
    folder = ROOT
    for index, part in enumerate(parts):
        if (folder / part / "__init__.py").is_file():
            folder = folder / part
            continue
        if (folder / f"{part}.py").is_file():
            return _defined_in(folder / f"{part}.py", parts[index + 1 :])
        return index > 0 and _defined_in(folder / "__init__.py", parts[index:])
    return True


def _defined_in(module: Path, rest: list[str]) -> bool:
    if not rest:
        return True
    names = module_names(module)
    if rest[0] not in names:
        return False
    members = names[rest[0]]
    return len(rest) == 1 or members is None or rest[1] in members


def path_exists(cited: str, citing: Path) -> bool:
    bases = [ROOT, ROOT / PACKAGE, ROOT / "test", citing.parent]
    bases += [ROOT / PACKAGE / sub for sub in SUBPACKAGES]  # docs/core.md: model/joints.py
    return any((base / cited).is_file() for base in bases)


def prose(path: Path) -> str:
    """The text where references are cited: a Python file's docstrings and comments, the
    whole of any other file."""
    text = path.read_text()
    if path.suffix != ".py":
        return text
    parts = []
    for node in ast.walk(ast.parse(text)):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr):
            value = body[0].value
            if isinstance(value, ast.Constant) and isinstance(value.value, str):
                parts.append(value.value)
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        if token.type == tokenize.COMMENT:
            parts.append(token.string)
    return "\n".join(parts)


def unresolved_references(path: Path) -> list[str]:
    """The references cited in ``path`` that do not resolve, in the order of the text."""
    found = _unresolved(path.read_text(), path)
    if found and path.suffix == ".py":  # (few files: the code around them is read only then)
        found = _unresolved(prose(path), path)
    return found


def _unresolved(text: str, path: Path) -> list[str]:
    found = []
    for match in FULL_NAME.finditer(text):
        name = match.group().rstrip(".")
        if not FILE_SUFFIX.search(name) and not resolves(name):
            found.append(name)
    for match in SHORT_NAME.finditer(text):
        name = match.group()
        if not FILE_SUFFIX.search(name) and not resolves(f"{PACKAGE}.{name}"):
            found.append(name)
    for match in PY_PATH.finditer(text):
        if not path_exists(match.group(), path):
            found.append(match.group())
    return found


@cache
def stale_names() -> frozenset[str]:
    """Every unresolved reference of the repository, as "file: name"."""
    stale = set()
    for path in cited_files():
        relative = path.relative_to(ROOT)
        stale.update(f"{relative}: {name}" for name in unresolved_references(path))
    return frozenset(stale)


def test_every_cited_name_of_the_package_exists():
    assert sorted(stale_names()) == []


def test_stale_names_are_found(tmp_path):
    citing = tmp_path / "cites.py"
    citing.write_text(
        '"""Uses ``core.regressor.regressor`` and irb140_dynamics.core.regressor.LINK_PARAMETERS,\n'
        "``ros.tracking``, irb140_dynamics.core.no_such_module, core.regressor.gone,\n"
        'core/regressor.py and nodes/id_node/no_such_file.py; docs/sim.md is no module."""\n'
    )
    assert unresolved_references(citing) == [
        "irb140_dynamics.core.no_such_module",
        "ros.tracking",
        "core.regressor.gone",
        "nodes/id_node/no_such_file.py",
    ]
