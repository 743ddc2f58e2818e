"""No dead code in the package: vulture (at 60 % confidence and up) finds no function, class,
method, attribute, variable, import or unreachable line of ``irb140_dynamics/`` that nothing
uses, the package, its tests and its benchmarks counted as users; nor is a name exported by
an ``__all__`` used by no other file. Each name vulture cannot see used (called by name by
a library) is in test/house/dead_code_whitelist.py with the reason."""

import ast
import re
from functools import cache
from pathlib import Path

import pytest

from ..support.paths import ROOT

vulture = pytest.importorskip("vulture", reason="vulture is in requirements/test.txt: ./scripts/test.sh installs it")

PACKAGE = "irb140_dynamics"
THIS_FILE = Path(__file__).resolve()  # not a user: its own test names dead code on purpose
USERS = (PACKAGE, "test", "bench", "launch")
MIN_CONFIDENCE = 60
WORD = re.compile(r"\w+")  # a name mentioned in a text: one of its runs of word characters (as \bname\b finds it)


def unused_code(paths) -> set[str]:
    """vulture's findings in files under ``PACKAGE``, as "file: name", scanning ``paths``."""
    scan = vulture.Vulture(verbose=False)
    scan.scavenge([str(path) for path in paths])
    found = set()
    for item in scan.get_unused_code(min_confidence=MIN_CONFIDENCE):
        relative = item.filename.resolve().relative_to(ROOT.resolve()).as_posix()
        if relative.startswith(f"{PACKAGE}/"):
            found.add(f"{relative}: {item.name}")
    return found


def exported_but_unused() -> set[str]:
    """Names in an ``__all__`` of the package that no other file of the package, the tests or
    the benchmarks mentions."""
    paths = [path for folder in USERS for path in (ROOT / folder).rglob("*.py") if path != THIS_FILE]
    texts = {path: path.read_text() for path in paths}
    words = {path: set(WORD.findall(text)) for path, text in texts.items()}  # a name is mentioned: one of them
    found = set()
    for path, text in texts.items():
        if not path.is_relative_to(ROOT / PACKAGE):
            continue
        for name in _all_of(text):
            assert WORD.fullmatch(name), f"{path}: __all__ names {name!r}, not a name"
            if not any(name in other for other_path, other in words.items() if other_path != path):
                found.add(f"{path.relative_to(ROOT).as_posix()}: {name}")
    return found


def _all_of(text: str) -> list[str]:
    for node in ast.parse(text).body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "__all__" for t in node.targets):
            return [element.value for element in node.value.elts if isinstance(element, ast.Constant)]
    return []


@cache
def dead_code() -> frozenset[str]:
    return frozenset(unused_code(ROOT / folder for folder in USERS) | exported_but_unused())


def test_no_dead_code_in_the_package():
    assert sorted(dead_code()) == []


def test_dead_code_is_found(tmp_path):
    module = tmp_path / PACKAGE / "orphan.py"
    module.parent.mkdir()
    module.write_text("def used():\n    return 1\n\n\ndef forgotten():\n    return used()\n")
    scan = vulture.Vulture(verbose=False)
    scan.scavenge([str(module)])
    assert [item.name for item in scan.get_unused_code(min_confidence=MIN_CONFIDENCE)] == ["forgotten"]
