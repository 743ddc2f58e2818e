"""Every node's command line as a user types it, decided before ROS starts: --help, ROS
arguments without --ros-args, an unknown argument, params files rcl should not be given.
Called in this process through each node's main(argv) (as its console script calls it),
with rclpy.init made to fail the test: none of these starts ROS or builds a node. The
process forms are smoke-tested in test/processes/test_node_command_line.py."""

from __future__ import annotations

import importlib
import re

import pytest
import rclpy

NODES = ("id_node", "payload_check_node", "sim_node", "demo_node", "trajectory_check_node")
MODEL_NODES = ("id_node", "payload_check_node", "sim_node")


def node_module(node: str):
    return importlib.import_module(f"irb140_dynamics.nodes.{node}.node")


@pytest.fixture
def no_ros(monkeypatch):
    def refuse(*_, **__):
        raise AssertionError("rclpy.init called: ROS was started")

    monkeypatch.setattr(rclpy, "init", refuse)


def main_status(node: str, *arguments: str) -> int:
    """The node's main() with argv ``node arguments...``: its exit status."""
    with pytest.raises(SystemExit) as stop:
        node_module(node).main([node, *arguments])
    return stop.value.code


@pytest.mark.parametrize("node", NODES)
@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_help_lists_the_parameters_and_starts_no_ros(no_ros, capfd, node, flag):
    code = main_status(node, flag)
    out, err = capfd.readouterr()
    assert code == 0 and err == "", (out, err)
    assert out.startswith(f"usage: {node} "), out
    for _, section in node_module(node).usage().sections:
        for spec in section:
            assert f"  {spec.name} (" in out, (spec.name, out)
    if node in MODEL_NODES:
        # ranges and units of the model's numbers, from the descriptors
        assert re.search(r"payload\.mass \(double, default 0\.0 kg, 0 to 1e\+06 kg\)", out), out
        assert "NAME.torque_limit (double, default 0.0 N m, 0 to 1e+07 N m)" in out, out


def one_fatal_line(capfd) -> str:
    out, err = capfd.readouterr()
    lines = (out + err).strip().splitlines()
    assert len(lines) == 1 and "[FATAL]" in lines[0] and "Traceback" not in out + err, (out, err)
    return lines[0]


@pytest.mark.parametrize("node", MODEL_NODES)
def test_a_ros_argument_without_ros_args_is_refused_with_the_fix(no_ros, capfd, node):
    assert main_status(node, "-p", "payload.mass:=2.0") == 2
    line = one_fatal_line(capfd)
    assert "add --ros-args" in line and f"{node} --ros-args -p payload.mass:=2.0" in line, line


def test_an_unknown_argument_is_refused(no_ros, capfd):
    assert main_status("id_node", "--verbose") == 2
    assert "'--verbose'" in one_fatal_line(capfd)


@pytest.mark.parametrize(
    "make_path, reason",
    [
        (lambda tmp: str(tmp / "missing.yaml"), "no such params file"),
        (lambda tmp: str(tmp), "a folder"),
        (lambda tmp: "/dev/zero", "not a regular file"),
        (lambda tmp: "/dev/urandom", "not a regular file"),
    ],
)
@pytest.mark.parametrize("node", MODEL_NODES)
def test_a_params_file_rcl_should_not_read_is_one_line(no_ros, capfd, tmp_path, node, make_path, reason):
    path = make_path(tmp_path)
    assert main_status(node, "--ros-args", "--params-file", path) == 1
    line = one_fatal_line(capfd)
    assert path in line and reason in line, line
