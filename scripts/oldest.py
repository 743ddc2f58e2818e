"""Helpers of scripts/test_oldest.sh (standard library only, run by the oldest venv's Python).

``oldest.py requirements FILE...`` prints the requirements with each ``>=`` lower bound made
exact, leaving out the ROS 2 wheels and colcon (the run needs no ROS) and what cannot be
installed beside the oldest NumPy (``WITHOUT``).

``oldest.py unimportable TEST_DIR [--ignore=PATH ...]`` prints, one per line, the given
``--ignore=PATH`` and one for each other test module that imports, when it is imported
(directly or through another module of the repository), a package this interpreter does
not have (rclpy, Pinocchio, ...), and says on stderr which package keeps each one out.
"""

import ast
import importlib.util
import re
import sys
from pathlib import Path

# Not installable beside numpy 1.26: every Pinocchio wheel from 3.0 on requires numpy >= 2.
# The tests that compare with Pinocchio run in the main suite (scripts/test.sh).
WITHOUT = {"pin": "its wheels require numpy >= 2"}
LEFT_OUT_PREFIXES = ("-r", "ros-jazzy-", "colcon-")


def oldest_requirements(files: list[str]) -> list[str]:
    lines = []
    for name in files:
        for line in Path(name).read_text().splitlines():
            requirement = line.partition("#")[0].strip()
            if not requirement or requirement.startswith(LEFT_OUT_PREFIXES):
                continue
            project = re.match(r"[A-Za-z0-9_.\-]+", requirement)[0]
            if project in WITHOUT:
                continue
            lowest = re.fullmatch(r"([A-Za-z0-9_.\-]+)\s*>=\s*([^,;\s]+).*", requirement)
            lines.append(f"{lowest[1]}=={lowest[2]}" if lowest else requirement)
    return lines


def imports_at_import_time(path: Path) -> set[str]:
    """Absolute names a module imports when it is imported (function bodies excepted)."""
    package = path.relative_to(Path.cwd()).parent.parts  # (of a module and of an __init__.py)
    names, pending = set(), list(ast.parse(path.read_text()).body)
    while pending:
        node = pending.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            continue
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join([*package[: len(package) - node.level + 1], *filter(None, [node.module])])
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names)
        pending.extend(ast.iter_child_nodes(node))
    return names


def missing_package(path: Path, seen: set[Path]) -> str | None:
    """The first package that importing ``path`` needs, directly or through the modules of
    the repository it imports, and that this interpreter lacks."""
    seen.add(path)
    for name in sorted(imports_at_import_time(path)):
        top = name.partition(".")[0]
        local = Path.cwd().joinpath(*name.split("."))
        if (Path.cwd() / top).is_dir():
            for candidate in (local.with_suffix(".py"), local / "__init__.py"):
                if candidate.is_file() and candidate not in seen:
                    found = missing_package(candidate, seen)
                    if found:
                        return found
        elif top not in sys.stdlib_module_names and importlib.util.find_spec(top) is None:
            return top
    return None


def unimportable(test_dir: str, ignores: list[str]) -> list[str]:
    """``ignores`` (pytest's --ignore=PATH), then one for each module that cannot be imported."""
    ignored = [Path.cwd() / argument.removeprefix("--ignore=") for argument in ignores]
    ignores = list(ignores)
    for path in sorted((Path.cwd() / test_dir).rglob("test_*.py")):
        if any(path.is_relative_to(folder) for folder in ignored):
            continue
        found = missing_package(path, set())
        if found:
            relative = path.relative_to(Path.cwd())
            print(f"left out: {relative} (imports {found})", file=sys.stderr)
            ignores.append(f"--ignore={relative}")
    return ignores


if __name__ == "__main__":
    command, *arguments = sys.argv[1:]
    if command == "requirements":
        print("\n".join(oldest_requirements(arguments)))
    elif command == "unimportable":
        print("\n".join(unimportable(arguments[0], arguments[1:])))
    else:
        sys.exit(f"oldest.py: unknown command {command!r}")
