"""Every node's command line as a user types it, as a process: --help and a refused params
file (smoke tests of what test/ros/test_node_command_line.py checks in-process for every
node), integers for doubles, the startup log, a params file rcl cannot parse, a bad URDF,
Ctrl-C at any moment."""

from __future__ import annotations

import re
import signal
import time

import pytest

from ..support.common import full_sweep
from ..support.node_process import console_script, handles_sigterm, interrupt, run_to_exit, start, wait_for_line
from ..support.paths import CONFIG

NODES = ("id_node", "payload_check_node", "sim_node", "demo_node")
MODEL_NODES = ("id_node", "payload_check_node", "sim_node")
START_LIMIT = 10.0  # s: a node that cannot start says so within this


def command(node: str, *arguments: str) -> list[str]:
    """The node as its console script runs it (through irb140_dynamics.entry)."""
    return console_script(node, *arguments)


def test_help_is_the_usage_on_standard_output_and_exit_0():
    code, output = run_to_exit(command("id_node", "--help"), timeout=60.0)
    assert code == 0 and "Traceback" not in output, output
    assert output.startswith("usage: id_node ") and "  payload.mass (double" in output, output
    assert "[INFO]" not in output and "ready" not in output, output  # no node was made


def test_a_missing_params_file_is_one_fatal_line_and_exit_1(tmp_path):
    path = str(tmp_path / "missing.yaml")
    started = time.monotonic()
    code, output = run_to_exit(command("sim_node", "--ros-args", "--params-file", path), timeout=60.0)
    assert code == 1 and "Traceback" not in output, output
    lines = output.strip().splitlines()
    assert len(lines) == 1 and "[FATAL]" in lines[0] and path in lines[0] and "no such params file" in lines[0], output
    assert time.monotonic() - started < START_LIMIT * 3  # no ROS, no model: quick even when loaded


def test_an_integer_for_a_double_is_taken_and_the_log_names_model_and_payload(tmp_path):
    process = start(command("id_node", "--ros-args", "-p", "payload.mass:=2"))
    lines: list[str] = []
    try:
        assert wait_for_line(process, "ready", lines), "".join(lines)
    finally:
        code, output = interrupt(process, lines)
    assert code == 0 and "Traceback" not in output, output
    assert "model: the built-in IRB-140 model" in output and str(CONFIG) in output, output
    assert "payload 2.0 kg" in output, output


def test_the_log_names_the_params_file(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("/**:\n  ros__parameters:\n    payload:\n      mass: 3\n")
    process = start(command("payload_check_node", "--ros-args", "--params-file", str(path)))
    lines: list[str] = []
    try:
        assert wait_for_line(process, "ready", lines), "".join(lines)
    finally:
        code, output = interrupt(process, lines)
    assert code == 0, output
    assert f"model: params file {path}" in output, output
    assert "3.0 kg payload" in output, output


def test_a_params_file_rcl_cannot_parse_is_one_line_with_its_line(tmp_path):
    path = tmp_path / "broken.yaml"
    path.write_text("garbage: [\n")
    code, output = run_to_exit(console_script("id_node", "--ros-args", "--params-file", str(path)))
    lines = output.strip().splitlines()
    assert code == 1 and len(lines) == 1, output  # rcl's own "Failed to parse global arguments" held back
    assert f"{path}:1:" in lines[0] and "garbage: [" in lines[0], output


# s after the node's code started (irb140_dynamics.entry.start: then NumPy, rclpy, ... are
# imported): while importing, initialising, building, running. Not before: a SIGINT in the
# interpreter's own startup (site, .pth files), before any code of the package runs, gets
# Python's "Fatal Python error: init_import_site", as for any Python program.
# Each node takes two: an early one and a later one (SIGNAL_DELAYS[k] and [k + 3], k the
# node's index mod 3), so that the nodes together cover every moment; each node at each
# with IRB140_SWEEP=full (docs/development.md).
SIGNAL_DELAYS = (0.0, 0.1, 0.3, 0.8, 1.5, 3.0)


def delays_of(node: str) -> tuple[float, ...]:
    if full_sweep():
        return SIGNAL_DELAYS
    k = NODES.index(node) % 3
    return SIGNAL_DELAYS[k], SIGNAL_DELAYS[k + 3]


def wait_for_the_package_code(process, timeout: float = 60.0) -> None:
    """Until the entry has started (its handler of SIGTERM installed)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        try:
            if handles_sigterm(process.pid):
                return
        except OSError:
            return
        time.sleep(0.002)


@pytest.mark.slow
@pytest.mark.parametrize("node", NODES)
def test_ctrl_c_at_any_moment_exits_0_with_at_most_one_line(node):
    """A Ctrl-C at each of the node's delays (importing, starting, running): exit 0, no
    traceback, at most one line besides the startup's own log lines."""
    for delay in delays_of(node):
        process = start(command(node))
        wait_for_the_package_code(process)
        time.sleep(delay)  # when the signal lands: any moment is right, none is waited for
        process.send_signal(signal.SIGINT)
        try:
            output, _ = process.communicate(timeout=60.0)
        finally:
            process.kill()
        assert process.returncode == 0 and "Traceback" not in output, (delay, output)
        other = [
            line
            for line in output.splitlines()
            if not re.search(r"\]: (model|ready|waiting for)|waiting for sim_node", line)
        ]
        assert len(other) <= 1, (delay, output)


@pytest.mark.parametrize("text", [None, "<robot name='x'><link name='a'/>"], ids=["missing", "malformed"])
@pytest.mark.parametrize("node", MODEL_NODES)
def test_a_bad_urdf_file_is_one_line_naming_it(tmp_path, node, text):
    path = tmp_path / "arm.urdf"
    if text is not None:
        path.write_text(text)
    arguments = ["--ros-args", "-p", "model.source:=robot_description", "-p", f"model.urdf_file:={path}"]
    started = time.monotonic()
    code, output = run_to_exit(command(node, *arguments), timeout=60.0)
    assert code == 1 and "Traceback" not in output, output
    fatal = [line for line in output.strip().splitlines() if "[FATAL]" in line]
    assert len(fatal) == 1 and str(path) in fatal[0] and len(fatal[0]) < 400, output
    assert time.monotonic() - started < START_LIMIT * 3
