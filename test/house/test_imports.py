"""The house's rules on imports (docs/architecture.md): the floors and rooms of .importlinter
kept, no import cycle at all (imports inside functions count, ``if TYPE_CHECKING:`` ones do
not), no module of the package loaded by name, and the checks themselves able to fail."""

import ast
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ..support.paths import ROOT

PACKAGE = "irb140_dynamics"
# importlib used on purpose, and what it loads: never a module of this package.
IMPORTLIB_ALLOWED = {
    "irb140_dynamics/ros/recorder.py": "message classes of a recorded topic's type (sensor_msgs.msg, ...)",
    "irb140_dynamics/native/compiler.py": "a kernel's extension module, compiled from generated C into the cache",
}


def lint_imports(root: Path) -> subprocess.CompletedProcess:
    command = [
        sys.executable,
        "-c",
        "import sys; from importlinter.cli import lint_imports_command as c; c()",
        "--config",
        str(root / ".importlinter"),
        "--no-cache",
        "--no-logo",
    ]
    return subprocess.run(command, cwd=root, capture_output=True, text=True, timeout=120)


def import_cycles(root: Path) -> list[list[str]]:
    """The import cycles of the package under ``root``, found in a process of their own (this
    one has the package imported already, from elsewhere perhaps)."""
    command = [sys.executable, "-m", "test.support.import_graph", str(root), PACKAGE]
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def test_the_floors_and_rooms_of_importlinter_are_kept():
    result = lint_imports(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr


def test_no_import_cycles():
    assert import_cycles(ROOT) == []


def test_no_module_of_the_package_is_loaded_by_name():
    users = {}
    for path in sorted((ROOT / PACKAGE).rglob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            named = isinstance(node, ast.Name) and node.id in ("importlib", "__import__")
            imported = (
                isinstance(node, (ast.Import, ast.ImportFrom))
                and any(alias.name.startswith("importlib") for alias in node.names)
                or isinstance(node, ast.ImportFrom)
                and (node.module or "").startswith("importlib")
            )
            if named or imported:
                users.setdefault(str(path.relative_to(ROOT)), node.lineno)
    assert set(users) <= set(IMPORTLIB_ALLOWED), users


@pytest.fixture
def package_copy(tmp_path):
    shutil.copytree(ROOT / PACKAGE, tmp_path / PACKAGE, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / ".importlinter", tmp_path)
    return tmp_path


def test_an_upward_import_breaks_the_floors(package_copy):
    dynamics = package_copy / PACKAGE / "core" / "dynamics.py"
    dynamics.write_text(dynamics.read_text() + "\nfrom irb140_dynamics.ros.runtime import spin  # noqa\n")
    result = lint_imports(package_copy)
    assert result.returncode != 0
    assert "BROKEN" in result.stdout


def test_a_node_importing_another_node_breaks_the_rules(package_copy):
    node = package_copy / PACKAGE / "nodes" / "demo_node" / "node.py"
    node.write_text(
        node.read_text() + "\n\ndef _upward():\n    from irb140_dynamics.nodes.id_node import settings  # noqa\n"
    )
    result = lint_imports(package_copy)
    assert result.returncode != 0
    assert "No node imports another node" in result.stdout


def test_a_process_started_from_the_core_breaks_the_rules(package_copy):
    kernels = package_copy / PACKAGE / "core" / "codegen" / "kernels.py"
    kernels.write_text(kernels.read_text() + "\n\ndef _compile():\n    import subprocess  # noqa\n")
    result = lint_imports(package_copy)
    assert result.returncode != 0
    assert "irb140_dynamics.core is not allowed to import subprocess" in " ".join(result.stdout.split())


PROCESS_CALLS = {"system", "popen", "fork", "forkpty", "posix_spawn", "posix_spawnp"}  # of os, and exec*, spawn*


def process_calls(root: Path) -> list[str]:
    """The calls in the core's source that start a process through ``os`` (imports of
    subprocess and multiprocessing are the core-starts-no-process contract's)."""
    found = []
    for path in sorted((root / PACKAGE / "core").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            of_os = isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "os"
            if of_os and (node.attr in PROCESS_CALLS or node.attr.startswith(("exec", "spawn"))):
                found.append(f"{path.relative_to(root)}:{node.lineno} os.{node.attr}")
    return found


def test_the_core_starts_no_process_through_os(package_copy):
    assert process_calls(ROOT) == []
    dynamics = package_copy / PACKAGE / "core" / "dynamics.py"
    dynamics.write_text(dynamics.read_text() + "\n\ndef _cc():\n    import os\n\n    os.system('cc')\n")
    (found,) = process_calls(package_copy)
    assert found.startswith("irb140_dynamics/core/dynamics.py:") and found.endswith(" os.system")


def test_a_cycle_inside_a_function_is_found(package_copy):
    model = package_copy / PACKAGE / "core" / "model" / "robot_model.py"
    model.write_text(model.read_text() + "\n\ndef _late():\n    from irb140_dynamics.core import dynamics  # noqa\n")
    assert any("irb140_dynamics.core.model.robot_model" in cycle for cycle in import_cycles(package_copy))


def test_no_module_imports_another_modules_private_names():
    found = []
    for path in sorted((ROOT / PACKAGE).rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module != "__future__":
                private = [a.name for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]
                found += [f"{path.relative_to(ROOT)}:{node.lineno} {name}" for name in private]
    assert found == []
