"""The launch files (launch/*.launch.py, installed under share/irb140_dynamics/launch/), tested
without ros2 launch (not on PyPI): each runs with no argument, names executables the
package installs and files it installs, and its nodes start with the parameters it gives
them, as ros2 launch would start them."""

from __future__ import annotations

import runpy
from pathlib import Path

import pytest
import yaml

from ..support.doc_blocks import console_scripts
from ..support.launch_stub import arguments_of, load_description, nodes_of, resolve
from ..support.node_process import console_script, interrupt, start, wait_for_line
from ..support.paths import ROOT

LAUNCH_FILES = sorted((ROOT / "launch").glob("*.launch.py"))
SCRIPTS = console_scripts(ROOT / "setup.py")
SHARE = Path("/opt/share/irb140_dynamics")  # where FindPackageShare points: mapped to the source tree
READY = 120.0  # s: a node's ready line, three nodes starting at once on two busy cores


def setup_keywords(monkeypatch) -> dict:
    """What setup.py passes to setuptools.setup (run in the repository, setup() captured)."""
    captured = {}
    import setuptools

    monkeypatch.setattr(setuptools, "setup", lambda **keywords: captured.update(keywords))
    monkeypatch.chdir(ROOT)
    runpy.run_path(str(ROOT / "setup.py"))
    return captured


def installed(monkeypatch) -> set[str]:
    """The share/ paths setup.py installs, as share/irb140_dynamics/<relative path>."""
    return {
        f"{target}/{Path(file).name}" for target, files in setup_keywords(monkeypatch)["data_files"] for file in files
    }


def in_source(path: str) -> Path:
    """An installed share path, in the source tree."""
    return ROOT / Path(path).relative_to(SHARE)


def test_every_launch_file_is_installed(monkeypatch):
    assert {path.name for path in LAUNCH_FILES} >= {
        "id_node.launch.py",
        "id_and_payload_check.launch.py",
        "sim_demo.launch.py",
    }
    paths = installed(monkeypatch)
    for path in LAUNCH_FILES:
        assert f"share/irb140_dynamics/launch/{path.name}" in paths


@pytest.mark.parametrize("launch_file", LAUNCH_FILES, ids=lambda path: path.name)
def test_runs_with_no_argument_on_installed_files_and_executables(launch_file, monkeypatch):
    description = load_description(launch_file, monkeypatch)
    arguments = arguments_of(description, {}, SHARE)
    assert all(value is not None for value in arguments.values()), arguments  # every argument has a default
    paths = installed(monkeypatch)
    for node in nodes_of(description, arguments, SHARE):
        assert node.package == "irb140_dynamics" and node.executable in SCRIPTS, node
        for item in resolve(node.parameters, arguments, SHARE):
            if isinstance(item, str):  # a params file: one the package installs
                assert f"share/irb140_dynamics/{Path(item).relative_to(SHARE)}" in paths, item
                assert in_source(item).is_file(), item


def node_command(node, arguments: dict) -> list[str]:
    """The node's command line as ros2 launch builds it (params files, then -p for a dict)."""
    command = console_script(node.executable, "--ros-args")
    if node.name:
        command += ["-r", f"__node:={node.name}"]
    for item in resolve(node.parameters, arguments, SHARE):
        if isinstance(item, str):
            command += ["--params-file", str(in_source(item))]
        else:
            for key, value in item.items():
                text = yaml.safe_dump(value, default_flow_style=True).strip().removesuffix("...").strip()
                command += ["-p", f"{key}:={text}"]
    return command


@pytest.mark.slow
@pytest.mark.parametrize(
    "launch_file, given, expected",
    [
        ("id_node.launch.py", {}, "payload 0.0 kg"),
        ("id_node.launch.py", {"payload_mass": "2"}, "payload 2.0 kg"),
        ("id_and_payload_check.launch.py", {"payload_mass": "1.5"}, "1.5 kg payload"),
        ("sim_demo.launch.py", {}, "ready"),
    ],
)
def test_its_nodes_start_with_its_parameters_and_stop_on_ctrl_c(launch_file, given, expected, monkeypatch):
    description = load_description(ROOT / "launch" / launch_file, monkeypatch)
    arguments = arguments_of(description, given, SHARE)
    processes = []
    try:
        for node in nodes_of(description, arguments, SHARE):
            lines: list[str] = []
            process = start(node_command(node, arguments))
            processes.append((process, lines))
            assert wait_for_line(process, "ready", lines, READY), "".join(lines)
    finally:
        stopped = [interrupt(process, lines) for process, lines in processes]
    output = "".join(text for _, text in stopped)
    assert all(code == 0 for code, _ in stopped), output
    assert "Traceback" not in output and "FATAL" not in output and "unknown parameter" not in output, output
    assert expected in output, output


@pytest.mark.parametrize("launch_file", LAUNCH_FILES, ids=lambda path: path.name)
@pytest.mark.parametrize("installed_rviz", [True, False], ids=["rviz_installed", "no_rviz"])
def test_rviz_true_starts_rviz_with_the_installed_config_where_installed(launch_file, installed_rviz, monkeypatch):
    from irb140_dynamics.ros import rviz_launch

    monkeypatch.setattr(rviz_launch, "rviz_installed", lambda: installed_rviz)
    description = load_description(launch_file, monkeypatch)
    assert all(node.package != "rviz2" for node in nodes_of(description, arguments_of(description, {}, SHARE), SHARE))
    arguments = arguments_of(description, {"rviz": "true"}, SHARE)
    rviz = [node for node in nodes_of(description, arguments, SHARE) if node.package == "rviz2"]
    if not installed_rviz:
        assert rviz == []
        notes = [e for e in description.entities if type(e).__name__ == "LogInfo"]
        assert len(notes) == 1 and "not installed" in notes[0].msg
        return
    assert len(rviz) == 1 and rviz[0].executable == "rviz2"
    option, config = resolve(rviz[0].arguments, arguments, SHARE)
    assert option == "-d" and config == str(SHARE / "rviz" / "dynamics.rviz")
    assert "share/irb140_dynamics/rviz/dynamics.rviz" in installed(monkeypatch) and in_source(config).is_file()


def test_the_rviz_config_shows_the_markers_in_the_base_link():
    config = yaml.safe_load((ROOT / "rviz" / "dynamics.rviz").read_text())
    manager = config["Visualization Manager"]
    displays = {display["Class"]: display for display in manager["Displays"]}
    assert {"rviz_default_plugins/RobotModel", "rviz_default_plugins/TF", "rviz_default_plugins/MarkerArray"} <= set(
        displays
    )
    assert displays["rviz_default_plugins/MarkerArray"]["Topic"]["Value"] == "/id_node/markers"
    assert manager["Global Options"]["Fixed Frame"] == "base_link"  # export_urdf's base link, the markers' frame
