"""Starting id_node: the default model, and one clear line for a bad model."""

import sys
import textwrap

import pytest

from ..support.node_process import module_command, run_to_exit, run_until_ready
from ..support.paths import CONFIG

ID_NODE = "irb140_dynamics.nodes.id_node.node"


def test_starts_with_the_default_model_and_stops_cleanly_on_ctrl_c():
    code, output = run_until_ready(module_command(ID_NODE))
    assert "ready: 6 joints" in output, output
    assert str(CONFIG) in output  # the defaults' file, from the source tree here
    assert code == 0, output


def test_ctrl_c_inside_a_callback_stops_cleanly():
    """Ctrl-C while a callback runs and messages wait: exit 0, no FATAL, no traceback
    (neither the callback cut short nor rclpy's C++ failing to build the next message:
    "RuntimeError: Unable to convert call argument '0'")."""
    code, output = run_to_exit(module_command("test.support.interrupting_node"), timeout=30.0)
    assert code == 0, output
    assert "FATAL" not in output and "Traceback" not in output, output
    assert "exit after" in output, output


CTRL_C_AS_A_FLAG = """
import os, signal, time
import rclpy
from irb140_dynamics.ros.runtime.spin import ctrl_c_as_a_flag
rclpy.init()
with ctrl_c_as_a_flag() as interrupted:
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(0.1)
    print("flag", bool(interrupted), "ok", rclpy.ok())
    try:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(1.0)
        print("second Ctrl-C ignored")
    except KeyboardInterrupt:
        print("second Ctrl-C raises")
    os.kill(os.getpid(), signal.SIGTERM)
    deadline = time.monotonic() + 5.0  # rclpy's signal thread shuts the context down
    while rclpy.ok() and time.monotonic() < deadline:
        time.sleep(0.01)
    print("SIGTERM ok", rclpy.ok())
context = rclpy.Context()
rclpy.init(context=context)
try:
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(1.0)
except KeyboardInterrupt:
    pass
time.sleep(0.2)
print("after ok", context.ok())
"""


def test_ctrl_c_as_a_flag_sets_rclpy_handlers_aside_and_back():
    """Inside: Ctrl-C only sets the flag, a second raises, SIGTERM still shuts rclpy down;
    after: rclpy's Ctrl-C handling is back (the context shuts down)."""
    code, output = run_to_exit([sys.executable, "-c", CTRL_C_AS_A_FLAG], timeout=30.0)
    assert code == 0, output
    assert "flag True ok True" in output, output
    assert "second Ctrl-C raises" in output, output
    assert "SIGTERM ok False" in output, output
    assert "after ok False" in output, output


def bad_file(tmp_path, text):
    path = tmp_path / "bad.yaml"
    path.write_text(textwrap.dedent(text))
    return str(path)


def config_with(old: str, new: str, tmp_path) -> str:
    text = CONFIG.read_text()
    assert old in text
    path = tmp_path / "edited.yaml"
    path.write_text(text.replace(old, new, 1))
    return str(path)


@pytest.mark.parametrize(
    "make_args, field",
    [
        (
            lambda tmp: ["--params-file", config_with("mass: 25.919999999999998", "mass: -25.92", tmp)],
            "joint_2.link.mass",
        ),
        (
            lambda tmp: ["--params-file", config_with("gravity: [0.0, 0.0, -9.81]", "gravity: [0, 0, -9.81]", tmp)],
            "gravity",
        ),
        (
            lambda tmp: ["--params-file", config_with("com: [-0.18, 0.0, 0.0]", "com: [-0.18, 0.0]", tmp)],
            "joint_2.link.com",
        ),
        (
            lambda tmp: ["--params-file", bad_file(tmp, "/**:\n  ros__parameters:\n    gravity: [0.0, 0.0\n")],
            "bad.yaml:3: Error parsing",
        ),
        (lambda tmp: ["--params-file", str(tmp / "missing.yaml")], "missing.yaml"),
        (lambda tmp: ["-p", "joint_4.link.inertia:=[1.0, 1.0, 3.0, 0.0, 0.0, 0.0]"], "joint_4.link.inertia"),
        (lambda tmp: ["-p", "payload.mass:=-2.0"], "payload.mass"),
        (lambda tmp: ["-p", "joint_names:=[a, b]"], "a.dh: missing"),
    ],
)
def test_bad_model_stops_startup_with_one_clear_line(tmp_path, make_args, field):
    code, output = run_to_exit(module_command(ID_NODE, *make_args(tmp_path)))
    assert code == 1, output
    assert "Traceback" not in output
    fatal = [line for line in output.splitlines() if "cannot start" in line]
    assert len(fatal) == 1 and field in fatal[0], output
