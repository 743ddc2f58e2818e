"""package.xml declares what the installed package imports, by rosdep key, so that ``rosdep
install --from-paths src`` brings everything every executable and launch file needs.

Each import of the run-time code (``irb140_dynamics/`` and ``launch/``, imports inside
functions included; the standard library and the package itself excluded) is mapped to a
rosdep key by ``ROSDEP_KEYS``; the test fails on an import the table does not know, on a key
package.xml does not declare, and on a declared key the table does not hold (a dependency
nobody can say why the package has)."""

import ast
import sys
import xml.etree.ElementTree as ElementTree
from pathlib import Path

from ..support.paths import ROOT

PACKAGE = "irb140_dynamics"
RUN_TIME_FOLDERS = ("irb140_dynamics", "launch")

# Import name -> rosdep key. ROS 2 packages are keys of their own (rosdistro's
# jazzy/distribution.yaml); the others are keys of ros/rosdistro's rosdep/python.yaml (read
# at its commit 8468e88 of 2026-08-22): the system package where Debian and Ubuntu have one,
# its "-pip" key (installed from PyPI) where they do not (MuJoCo, rosbags).
ROSDEP_KEYS = {
    "rclpy": "rclpy",
    "ament_index_python": "ament_index_python",
    "builtin_interfaces": "builtin_interfaces",
    "rcl_interfaces": "rcl_interfaces",
    "rosgraph_msgs": "rosgraph_msgs",
    "std_msgs": "std_msgs",
    "std_srvs": "std_srvs",
    "sensor_msgs": "sensor_msgs",
    "geometry_msgs": "geometry_msgs",
    "visualization_msgs": "visualization_msgs",
    "trajectory_msgs": "trajectory_msgs",
    "diagnostic_msgs": "diagnostic_msgs",
    "launch": "launch",
    "launch_ros": "launch_ros",
    "numpy": "python3-numpy",
    "yaml": "python3-yaml",
    "scipy": "python3-scipy",
    "matplotlib": "python3-matplotlib",
    "sympy": "python3-sympy",
    "mujoco": "python3-mujoco-pip",
    "rosbags": "python3-rosbags-pip",
}
# Declared for what the nodes publish next (markers, wrenches), before any import uses them.
DECLARED_AHEAD = {"geometry_msgs", "visualization_msgs"}


def third_party_imports(folders=RUN_TIME_FOLDERS, root: Path = ROOT) -> dict[str, str]:
    """Top-level name of every absolute import outside the standard library and the package
    -> the first file (relative to ``root``) and line that imports it."""
    found = {}
    for folder in folders:
        for path in sorted((root / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Import):
                    names = [alias.name for alias in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names = [node.module]
                else:
                    continue
                for name in names:
                    top = name.partition(".")[0]
                    if top not in sys.stdlib_module_names and top != PACKAGE:
                        found.setdefault(top, f"{path.relative_to(root)}:{node.lineno}")
    return found


def declared_keys(package_xml: Path = ROOT / "package.xml") -> set[str]:
    root = ElementTree.parse(package_xml).getroot()
    tags = ("depend", "exec_depend")
    return {element.text.strip() for tag in tags for element in root.iter(tag)}


def test_every_import_of_the_run_time_code_has_a_rosdep_key():
    unknown = {name: where for name, where in third_party_imports().items() if name not in ROSDEP_KEYS}
    assert unknown == {}, "add each to ROSDEP_KEYS (a key of rosdep/python.yaml) and to package.xml"


def test_every_imported_key_is_declared_in_package_xml():
    declared = declared_keys()
    missing = {name: ROSDEP_KEYS[name] for name in third_party_imports() if ROSDEP_KEYS.get(name) not in declared}
    assert missing == {}


def test_every_declared_key_is_accounted_for():
    assert declared_keys() - set(ROSDEP_KEYS.values()) == set()


def test_every_key_of_the_table_is_imported_or_declared_ahead():
    unused = set(ROSDEP_KEYS) - set(third_party_imports()) - DECLARED_AHEAD
    assert unused == set()


def test_the_scan_sees_imports_inside_functions(tmp_path):
    module = tmp_path / "pkg" / "late.py"
    module.parent.mkdir()
    module.write_text(
        "import os\nfrom . import sibling\n\ndef f():\n    import mujoco.viewer\n    from irb140_dynamics import core\n"
    )
    assert third_party_imports(("pkg",), tmp_path) == {"mujoco": "pkg/late.py:5"}


def test_package_xml_is_format_3_and_ament_python():
    root = ElementTree.parse(ROOT / "package.xml").getroot()
    assert root.get("format") == "3"
    assert root.findtext("export/build_type") == "ament_python"
    assert "revolute and prismatic" in " ".join(root.findtext("description").split())
