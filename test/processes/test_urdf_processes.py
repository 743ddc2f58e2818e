"""id_node as its own process on a URDF: robot_description in a params file (a YAML block
string, the way the README shows), and a bad URDF file stopping startup in one line."""

import textwrap

import numpy as np
from sensor_msgs.msg import JointState

from ..support.node_process import TIMEOUT, module_command, run_to_exit
from ..support.urdf_support import ARMS, arm_text, expected_gravity

PARAMS = """\
/**:
  ros__parameters:
    model:
      source: robot_description
      tip_link: {tip}
    robot_description: |
{urdf}
"""


def test_robot_description_from_a_params_file(tmp_path, probe, process):  # noqa: F811
    text, tip = arm_text("panda"), ARMS["panda"][1]
    params = tmp_path / "panda.yaml"
    params.write_text(PARAMS.format(tip=tip, urdf=textwrap.indent(text, " " * 6)))
    process("irb140_dynamics.nodes.id_node.node", "--params-file", str(params))
    received = []
    probe.create_subscription(JointState, "gravity_torques", received.append, 10)
    joint_states = probe.create_publisher(JointState, "joint_states", 10)
    q = np.random.default_rng(4).uniform(-2.0, 2.0, 7)
    state = JointState(name=[f"panda_joint{i}" for i in range(1, 8)], position=q.tolist())
    probe.spin_until(lambda: received, timeout=TIMEOUT, each=lambda: joint_states.publish(state))
    np.testing.assert_allclose(received[-1].effort, expected_gravity(text, tip, q), rtol=1e-9, atol=1e-9)


def test_bad_urdf_file_stops_startup_with_one_line(tmp_path):
    bad = tmp_path / "bad.urdf"
    bad.write_text(arm_text("ur5").replace('type="revolute"', 'type="floating"', 1))
    args = ["-p", "model.source:=robot_description", "-p", f"model.urdf_file:={bad}", "-p", "model.tip_link:=tool0"]
    code, output = run_to_exit(module_command("irb140_dynamics.nodes.id_node.node", *args))
    assert code == 1 and "Traceback" not in output, output
    [fatal] = [line for line in output.splitlines() if "cannot start" in line]
    assert f'model.urdf_file {bad}: URDF joint "shoulder_pan_joint": a floating joint' in fatal, output
