"""One arm from the same files for every node and every tool (core.io.arm_source.read_arm):
a URDF whose base link is turned against its root, with gravity given in the params file
(in the root link's frame, as docs/urdf.md states); a params file giving only the payload
(merged over the IRB-140); a misspelt name and a parameter of a joint the arm does not have
(each tool refuses them in one line, exit status 2, naming the nearest known name; each
node warns, naming the same)."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from irb140_dynamics.core import RigidBody, irb140
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode
from irb140_dynamics.nodes.sim_node.node import SimNode
from irb140_dynamics.nodes.trajectory_check_node.node import TrajectoryCheckNode
from irb140_dynamics.tools import equations, excitation, export_urdf, identify, load_diagram, retime

from ..support.paths import URDF_DATA
from ..support.ros_harness import running

NODES = (IdNode, PayloadCheckNode, SimNode, TrajectoryCheckNode)
ROOT_TURN = (0.6, -0.9, 0.3)  # rpy [rad] of the UR5's base_link in the root link's frame
GRAVITY_IN_ROOT = [0.0, 0.0, -9.81]


def tool_arguments(tmp_path) -> dict:
    """Each tool (module) with the arguments it needs besides the model's; outputs in tmp_path."""
    recording = tmp_path / "recording.csv"
    recording.write_text("t,q_1\n")  # never read: the arm is read (or refused) first
    return {
        "load_diagram": (load_diagram, ["--out", str(tmp_path / "diagram")]),
        "excitation": (excitation, ["--out", str(tmp_path / "excitation.yaml")]),
        "identify": (identify, [str(recording), "--out", str(tmp_path / "identified.yaml"), "--quiet"]),
        "identify --payload-only": (
            identify,
            [str(recording), "--out", str(tmp_path / "load.yaml"), "--quiet", "--payload-only"],
        ),
        "retime": (retime, [str(tmp_path / "in.yaml"), "--check-only"]),
        "equations": (equations, ["--form", "c", "--out", str(tmp_path / "equations")]),
        "export_urdf": (export_urdf, ["--out", str(tmp_path / "arm.urdf")]),
    }


def params_file(folder, name, parameters) -> str:
    path = folder / name
    path.write_text(yaml.safe_dump({"/**": {"ros__parameters": parameters}}))
    return str(path)


def turned_urdf(folder) -> str:
    """The UR5 (test/data/urdf, BSD) with its base_link turned against the root link 'world'."""
    text = (URDF_DATA / "ur5.urdf").read_text()
    fixed = '<child link="base_link"/>\n    <origin rpy="0.0 0.0 0.0" xyz="0.0 0.0 0.0"/>'
    assert fixed in text
    turned = f'<child link="base_link"/>\n    <origin rpy="{" ".join(map(str, ROOT_TURN))}" xyz="0.1 0.0 0.5"/>'
    path = folder / "turned_ur5.urdf"
    path.write_text(text.replace(fixed, turned))
    return str(path)


def tool_arm(tool, model_arguments):
    """The arm as the tool's main reads it: its own parser, then its ``arm_of``."""
    module, own = tool
    return module.arm_of(module.parser().parse_args([*own, *model_arguments])).model


def tool_status(tool, arguments, capfd) -> tuple[int, str]:
    module, own = tool
    argv = [*own, *arguments]
    status = module.main(["export_urdf", *argv] if module is export_urdf else argv)
    return status, capfd.readouterr().err


def node_model(make_node, cli_args):
    with running(make_node, cli_args=["--ros-args", *cli_args]) as harness:
        assert harness.spin_until(lambda: harness.node.model is not None), f"{make_node.__name__}: no model"
        return harness.node.model


def test_a_turned_base_urdf_with_gravity_in_the_params_file(tmp_path):
    urdf = turned_urdf(tmp_path)
    drive = {"shoulder_pan_joint": {"torque_limit": 42.0, "friction": {"viscous": 1.5}}}  # what URDF has no place for
    chain = {"model.base_link": "base_link", "model.tip_link": "tool0", "gravity": GRAVITY_IN_ROOT, **drive}
    described = params_file(
        tmp_path, "described.yaml", {"model.source": "robot_description", "model.urdf_file": urdf, **chain}
    )
    beside = params_file(tmp_path, "gravity.yaml", {"gravity": GRAVITY_IN_ROOT, **drive})
    expected_gravity = Rotation.from_euler("xyz", ROOT_TURN).as_matrix().T @ np.array(GRAVITY_IN_ROOT)
    assert abs(expected_gravity[2]) < 9.0  # turned: not along the base's -z
    models = {}
    for make_node in NODES:
        models[make_node.__name__] = node_model(make_node, ["--params-file", described])
    for name, tool in tool_arguments(tmp_path).items():
        models[name] = tool_arm(tool, ["--params-file", described])
        models[f"{name} --urdf"] = tool_arm(
            tool, ["--params-file", beside, "--urdf", urdf, "--base", "base_link", "--tip", "tool0"]
        )
    reference = models["IdNode"]
    assert reference.joint_names[0] == "shoulder_pan_joint" and reference.n == 6
    np.testing.assert_allclose(reference.gravity, expected_gravity, rtol=0, atol=1e-12)
    pan = reference.joints[0]
    assert (pan.torque_limit, pan.friction.viscous) == (42.0, 1.5), pan
    differing = {name: model.gravity for name, model in models.items() if model != reference}
    assert not differing, f"{reference.gravity} by IdNode; {differing}"


def test_a_partial_params_file_is_merged_over_the_irb140(tmp_path):
    partial = params_file(tmp_path, "payload.yaml", {"payload": {"mass": 2.0}})
    expected = irb140(payload=RigidBody(2.0))
    models = {make_node.__name__: node_model(make_node, ["--params-file", partial]) for make_node in NODES}
    for name, tool in tool_arguments(tmp_path).items():
        models[name] = tool_arm(tool, ["--params-file", partial])
    assert {name for name, model in models.items() if model != expected} == set()


def test_retime_reads_the_irb140_without_a_params_file(tmp_path):
    module, own = tool_arguments(tmp_path)["retime"]
    assert tool_arm((module, own), []) == irb140()


@pytest.mark.parametrize(
    ("given", "unknown", "nearest"),
    [
        ({"payload": {"masss": 2.0}}, ["-p", "joint_6.torque_limt:=3.0"], ["payload.mass", "joint_6.torque_limit"]),
        ({}, ["-p", "joint_7.torque_limit:=3.0"], ["joint_6.torque_limit", "the arm has no joint joint_7"]),
        ({"joint_1": {"dh": {"a": 0.1}}}, [], ["joint_1.dh is one parameter, not a mapping"]),
    ],
    ids=["typos", "no such joint", "a list as a mapping"],
)
def test_an_unknown_name_is_refused_by_every_tool_and_warned_about_by_every_node(
    tmp_path, capfd, given, unknown, nearest
):
    path = params_file(tmp_path, "arm.yaml", given)
    names = [text.split(":=")[0] for text in unknown[1::2]] + [
        f"{group}.{key}" if not isinstance(value, dict) else f"{group}.{key}.{next(iter(value))}"
        for group, entries in given.items()
        for key, value in entries.items()
    ]
    hints = [f"did you mean {name}?" if " " not in name else name for name in nearest]  # names, or words
    for name, tool in tool_arguments(tmp_path).items():
        status, error = tool_status(tool, ["--params-file", path, *unknown], capfd)
        assert status == 2 and error.count("\n") == 1, (name, status, error)
        assert all(text in error for text in names + hints), (name, error)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arm.yaml", "recording.csv"]  # nothing written
    capfd.readouterr()
    for make_node in NODES:
        assert node_model(make_node, ["--params-file", path, *unknown]) == irb140()
        warnings = [line for line in capfd.readouterr().err.splitlines() if "unknown parameter" in line]
        assert all(any(text in line for line in warnings) for text in names + hints), (make_node.__name__, warnings)


@pytest.mark.parametrize("make_node", NODES, ids=lambda make: make.__name__)
def test_a_payload_link_on_an_arm_of_parameters_is_refused_not_ignored(make_node):
    """payload.link names a URDF link: on the default arm (DH parameters) a node refuses it,
    as the tools do, rather than leaving the payload on the flange without a word."""
    with (
        pytest.raises(ValueError, match=r"payload.link names a URDF link"),
        running(make_node, cli_args=["--ros-args", "-p", "payload.link:=link_3"]),
    ):
        pass
