"""Starting the nodes with bad values, unknown names or Ctrl-C: one clear line, no traceback."""

import os
import re
import signal
import time

import numpy as np
import pytest
import yaml

from ..support.common import random_model
from ..support.node_process import module_command, one_fatal_line, run_to_exit, run_until_ready, start
from ..support.paths import CONFIG, ROOT

ID_NODE = "irb140_dynamics.nodes.id_node.node"
PAYLOAD_CHECK_NODE = "irb140_dynamics.nodes.payload_check_node.node"


def params_file(tmp_path, parameters: dict, name="params.yaml") -> str:
    path = tmp_path / name
    path.write_text(yaml.safe_dump({"/**": {"ros__parameters": parameters}}))
    return str(path)


@pytest.mark.parametrize(
    "module, args, message",
    [
        (ID_NODE, ["-p", "qos.depth:=3000000000"], "qos.depth: must be between 1 and 10000, got 3000000000"),
        (ID_NODE, ["-p", "qos.depth:=0"], "qos.depth: must be between 1 and 10000, got 0"),
        (
            ID_NODE,
            ["-p", "acceleration.cutoff_frequency:=.inf"],
            "acceleration.cutoff_frequency: must be between 0.001 and 1e+06, got inf",
        ),
        (
            PAYLOAD_CHECK_NODE,
            ["-p", "diagnostics.period:=.inf"],
            "diagnostics.period: must be between 0 and 3600, got inf",
        ),
        (
            PAYLOAD_CHECK_NODE,
            ["-p", "diagnostics.period:=1e12"],
            "diagnostics.period: must be between 0 and 3600, got 1000000000000.0",
        ),
        (
            PAYLOAD_CHECK_NODE,
            ["-p", "diagnostics.period:=0.001"],
            "diagnostics.period: must be 0 (only on ~/check) or between 0.1 and 3600 s, got 0.001",
        ),
    ],
)
def test_a_value_out_of_its_range_stops_startup_with_one_line(module, args, message):
    fatal = one_fatal_line(*run_to_exit(module_command(module, *args)))
    assert fatal.endswith(f"cannot start: {message}"), fatal


@pytest.mark.parametrize(
    "content, expected",
    [
        (b"/**:\n  ros__parameters:\n    payload.mass: \xff\xfe 3.0\n", re.compile(r"binary\.yaml: not UTF-8 text")),
        (np.random.default_rng(8).bytes(400), re.compile(r"binary\.yaml(:\d+)?: ")),
    ],
)
def test_a_binary_params_file_stops_startup_with_one_line(tmp_path, content, expected):
    path = tmp_path / "binary.yaml"
    path.write_bytes(content)
    fatal = one_fatal_line(*run_to_exit(module_command(ID_NODE, "--params-file", str(path))))
    assert expected.search(fatal), fatal


def test_the_readme_startup_error_is_what_the_node_prints(tmp_path):
    text = CONFIG.read_text().replace("mass: 25.919999999999998", "mass: -25.92", 1)
    path = tmp_path / "negative.yaml"
    path.write_text(text)
    fatal = one_fatal_line(*run_to_exit(module_command(ID_NODE, "--params-file", str(path))))
    line = "[FATAL] [id_node]: cannot start: joint_2.link.mass: must be between 0 and 1e+06, got -25.92"
    assert re.sub(r" \[\d+\.\d+\]", "", fatal) == line
    assert f"    {line}\n" in (ROOT / "README.md").read_text()


def test_unknown_parameters_are_warned_about_with_the_nearest_name(tmp_path):
    path = params_file(
        tmp_path,
        {
            "payload": {"mas": 3.0},
            "joint_1": {"dh": {"a": 0.0, "alpha": 1.5707963267948966, "d": 0.2, "theta_offset": 0.0}},
            "rated_payload": {"mass": 5.0},  # payload_check_node's: no word from id_node
        },
    )
    code, output = run_until_ready(module_command(ID_NODE, "--params-file", path, "-p", "acceleration.mod:=zero"))
    assert code == 0, output
    warnings = [line.split("]: ", 1)[1] for line in output.splitlines() if "[WARN]" in line]
    assert warnings == [
        "unknown parameter acceleration.mod (ignored); did you mean acceleration.mode?",
        "unknown parameter payload.mas (ignored); did you mean payload.mass?",
        "unknown parameters joint_1.dh.a, joint_1.dh.alpha, joint_1.dh.d, joint_1.dh.theta_offset (ignored): "
        "joint_1.dh is one parameter, not a mapping: standard DH row [a, alpha, d, theta_offset] [m, rad, m, rad]",
    ], output


def twenty_joints(tmp_path) -> str:
    model = random_model(np.random.default_rng(20), 20)

    def typed(key, value):
        if key == "joint_names":
            return value
        return [float(x) for x in value] if isinstance(value, list) else float(value)

    parameters = {key: typed(key, value) for key, value in model.to_params().items()}
    return params_file(tmp_path, parameters, "twenty.yaml")


def test_ctrl_c_during_startup_is_one_line(tmp_path):
    """payload_check_node with 20 joints: its first analysis takes seconds; Ctrl-C while the
    node waits for it (or declares its parameters): the stop asked for, exit 0, one line."""
    process = start(module_command(PAYLOAD_CHECK_NODE, "--params-file", twenty_joints(tmp_path)))
    try:
        os.set_blocking(process.stdout.fileno(), False)
        lines, deadline = [], time.monotonic() + 30
        while not any("model: params file" in line for line in lines):
            assert time.monotonic() < deadline and process.poll() is None, "".join(lines)
            line = process.stdout.readline()
            lines.append(line) if line else time.sleep(0.02)
        process.send_signal(signal.SIGINT)
        rest, _ = process.communicate(timeout=20)
    finally:
        process.kill()
    output = "".join(lines) + (rest or "")
    assert "ready:" not in output and "Failed to publish" not in output, output  # nor rosout's complaint
    assert process.returncode == 0 and "Traceback" not in output and "FATAL" not in output, output
    assert output.rstrip().splitlines()[-1].endswith("interrupted (Ctrl-C) before the node was ready"), output
