"""Every node's command line as a user types it: --help, ROS arguments without --ros-args,
integers for doubles, the startup log, params files refused in one line, Ctrl-C at any
moment."""

from __future__ import annotations

import re
import signal
import sys
import time

import pytest

from ..support.common import full_sweep
from ..support.node_process import interrupt, module_command, run_to_exit, start, wait_for_line
from ..support.paths import CONFIG

NODES = ("id_node", "payload_check_node", "sim_node", "demo_node")
MODEL_NODES = ("id_node", "payload_check_node", "sim_node")
START_LIMIT = 10.0  # s: a node that cannot start says so within this


def command(node: str, *arguments: str) -> list[str]:
    """The node as its console script runs it (nodes.quiet_ctrl_c while importing)."""
    return [sys.executable, "-m", f"irb140_dynamics.nodes.{node}", *arguments]


@pytest.mark.parametrize("node", NODES)
@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_help_lists_the_parameters_and_starts_no_ros(node, flag):
    code, output = run_to_exit(command(node, flag), timeout=60.0)
    assert code == 0 and "Traceback" not in output, output
    assert output.startswith(f"usage: {node} "), output
    assert "[INFO]" not in output and "ready" not in output, output  # no node was made
    specs = __import__(f"irb140_dynamics.nodes.{node}.node", fromlist=["usage"]).usage().sections
    for _, section in specs:
        for spec in section:
            assert f"  {spec.name} (" in output, (spec.name, output)
    if node in MODEL_NODES:
        # ranges and units of the model's numbers, from the descriptors
        assert re.search(r"payload\.mass \(double, default 0\.0 kg, 0 to 1e\+06 kg\)", output), output
        assert "NAME.torque_limit (double, default 0.0 N m, 0 to 1e+07 N m)" in output, output


@pytest.mark.parametrize("node", MODEL_NODES)
def test_a_ros_argument_without_ros_args_is_refused_with_the_fix(node):
    started = time.monotonic()
    code, output = run_to_exit(command(node, "-p", "payload.mass:=2.0"), timeout=60.0)
    assert code == 2 and "Traceback" not in output, output
    lines = output.strip().splitlines()
    assert len(lines) == 1, output
    assert "add --ros-args" in lines[0] and f"{node} --ros-args -p payload.mass:=2.0" in lines[0], output
    assert time.monotonic() - started < START_LIMIT * 3  # no ROS, no model: quick even when loaded


def test_an_unknown_argument_is_refused():
    code, output = run_to_exit(command("id_node", "--verbose"), timeout=60.0)
    assert code == 2 and len(output.strip().splitlines()) == 1 and "'--verbose'" in output, output


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
def test_a_params_file_rcl_should_not_read_is_one_line(tmp_path, node, make_path, reason):
    path = make_path(tmp_path)
    started = time.monotonic()
    code, output = run_to_exit(command(node, "--ros-args", "--params-file", path), timeout=60.0)
    elapsed = time.monotonic() - started
    assert code == 1 and "Traceback" not in output, output
    lines = output.strip().splitlines()
    assert len(lines) == 1 and "[FATAL]" in lines[0] and path in lines[0] and reason in lines[0], output
    assert elapsed < START_LIMIT * 3, elapsed  # (10 s on an idle machine; the slack is for load)


def test_a_params_file_rcl_cannot_parse_is_one_line_with_its_line(tmp_path):
    path = tmp_path / "broken.yaml"
    path.write_text("garbage: [\n")
    code, output = run_to_exit(module_command("irb140_dynamics.nodes.id_node.node", "--params-file", str(path)))
    lines = output.strip().splitlines()
    assert code == 1 and len(lines) == 1, output  # rcl's own "Failed to parse global arguments" held back
    assert f"{path}:1:" in lines[0] and "garbage: [" in lines[0], output


# s after the node's code started (NumPy being imported): while importing, initialising,
# building, running. Not before: a SIGINT in the interpreter's own startup (site, .pth
# files), before any code of the package runs, gets Python's "Fatal Python error:
# init_import_site", as for any Python program.
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
    """Until the process has NumPy loaded: nodes.quiet_ctrl_c is in force by then."""
    deadline = time.monotonic() + timeout
    maps = f"/proc/{process.pid}/maps"
    while time.monotonic() < deadline and process.poll() is None:
        try:
            with open(maps) as stream:
                if "numpy" in stream.read():
                    return
        except OSError:
            return
        time.sleep(0.005)


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
