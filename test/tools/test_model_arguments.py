"""The model of the tools: a parameter file (parameters or robot_description), a URDF with
base and tip, -p overrides (core/io/arm_source.py, through tools.common.arm_of); excitation,
identify and export_urdf on a URDF arm, identify's outputs loaded back, and the offline
tools without ROS."""

import contextlib
import io
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from irb140_dynamics.core import rnea_batch
from irb140_dynamics.core.io.arm_source import given_values, read_arm, read_urdf_file
from irb140_dynamics.core.io.params_file import load_model, read_parameter_file
from irb140_dynamics.core.regressor import inertial_parameters
from irb140_dynamics.core.urdf import load_urdf
from irb140_dynamics.tools import excitation as excitation_tool
from irb140_dynamics.tools import identify as identify_tool

from ..support.common import load_yaml
from ..support.paths import CONFIG, ROOT
from ..support.simulated_ur5 import BASE, TIP, UR5_URDF, excitation, true_ur5, write_csv

RATE = 200.0


def tool_model(params_file=None, urdf_file=None, base_link=None, tip_link=None, overrides=None, defaults_file=None):
    """The arm as a tool reads it: the params file over the defaults, then the overrides."""
    values = given_values([params_file] if params_file else [], (overrides or {}).items())
    urdf = read_urdf_file(urdf_file) if urdf_file is not None else None
    defaults = read_parameter_file(defaults_file) if defaults_file else None
    folder = Path(params_file).parent if params_file else None
    return read_arm(values, defaults, urdf, base_link, tip_link, str(params_file) if params_file else None, folder)


def described(folder, **extra) -> str:
    """A parameter file naming the UR5's URDF (copied beside it, given relative)."""
    (folder / "ur5.urdf").write_text(UR5_URDF.read_text())
    parameters = {
        "model.source": "robot_description",
        "model.urdf_file": "ur5.urdf",
        "model.base_link": BASE,
        "model.tip_link": TIP,
        **extra,
    }
    path = folder / "arm.yaml"
    path.write_text(yaml.safe_dump({"/**": {"ros__parameters": parameters}}))
    return str(path)


def test_a_params_file_naming_a_urdf_gives_the_urdf_model(tmp_path):
    direct = tool_model(urdf_file=UR5_URDF, base_link=BASE, tip_link=TIP)
    assert (
        direct.urdf is not None
        and direct.model.joint_names == load_urdf(UR5_URDF.read_text(), BASE, TIP).model.joint_names
    )
    named = tool_model(described(tmp_path, gravity=[0.0, 0.0, -9.0]), defaults_file=CONFIG)
    assert inertial_parameters(named.model) == pytest.approx(inertial_parameters(direct.model), abs=0)
    assert named.model.gravity == (0.0, 0.0, -9.0) and direct.model.gravity == (0.0, 0.0, -9.81)
    overridden = tool_model(urdf_file=UR5_URDF, base_link=BASE, tip_link=TIP, overrides={"payload.mass": 2.0})
    assert overridden.model.payload.mass == 2.0
    assert tool_model(defaults_file=CONFIG).model.n == 6  # no file: the package's IRB-140
    # what URDF has no place for, for the chain's joints, from the params file; defaults never
    extra = {"shoulder_pan_joint.acceleration_limit": 5.0, "shoulder_pan_joint.armature": 0.2, "joint_1.armature": 9.0}
    given = tool_model(described(tmp_path, **extra), defaults_file=CONFIG).model
    assert given.joints[0].acceleration_limit == 5.0 and given.joints[0].armature == 0.2
    assert given.joints[1].acceleration_limit == direct.model.joints[1].acceleration_limit
    assert [j.armature for j in given.joints[1:]] == [j.armature for j in direct.model.joints[1:]]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (dict(urdf_file="/no/such.urdf"), "URDF: /no/such.urdf: no such URDF file"),
        (dict(urdf_file=UR5_URDF, tip_link="nowhere"), "no link 'nowhere'"),
        (dict(urdf_file=UR5_URDF, base_link="nowhere"), "nowhere"),
        (dict(base_link=BASE), "--base and --tip choose a URDF's chain"),
        (dict(overrides={"model.source": "topic"}), "model.source: must be one of"),
        (dict(overrides={"model.source": "robot_description"}), "neither robot_description nor model.urdf_file"),
    ],
)
def test_bad_model_arguments_are_one_line(kwargs, message):
    with pytest.raises(ValueError) as error:
        tool_model(defaults_file=CONFIG, **kwargs)
    assert message in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda tmp: "/dev/zero", "/dev/zero: not a regular file"),
        (lambda tmp: tmp, "is a folder"),
        (lambda tmp: tmp / "missing.yaml", "missing.yaml: no such parameter file"),
        (lambda tmp: _written(tmp / "digits.yaml", "/**:\n  ros__parameters:\n    a: " + "9" * 5000), "digits.yaml: "),
    ],
)
def test_a_params_file_that_is_no_file_or_no_yaml_is_named_with_the_reason(tmp_path, make, message):
    """The reasons read_parameter_file gives (a device, a folder: not 'no such file'; a
    number YAML cannot convert: the file named)."""
    with pytest.raises(ValueError) as error:
        tool_model(make(tmp_path), defaults_file=CONFIG)
    assert message in str(error.value) and "\n" not in str(error.value), error.value


def _written(path, text):
    path.write_text(text)
    return path


def test_excitation_for_a_urdf_arm(tmp_path):
    out = tmp_path / "excitation.yaml"
    arguments = ["--out", str(out), "--urdf", str(UR5_URDF), "--base", BASE, "--tip", TIP, "--iterations", "0"]
    with contextlib.redirect_stdout(io.StringIO()):
        assert excitation_tool.main(arguments) == 0
    document = load_yaml(out.read_text())
    assert document["joint_names"] == list(true_ur5().joint_names)


@pytest.fixture(scope="module")
def identified(tmp_path_factory):
    """identify on the UR5 (torques of the true arm by rnea, 0.5 % noise) with its URDF named
    by a params file (robot_description) as the prior; its outputs."""
    folder = tmp_path_factory.mktemp("identify")
    arm = true_ur5()
    t = np.arange(int(16.0 * RATE)) / RATE
    Q, QD, QDD = excitation(arm, 1).evaluate(t)
    tau = rnea_batch(arm, Q, QD, QDD)
    tau += np.random.default_rng(3).normal(size=tau.shape) * 0.005 * np.abs(tau).max(axis=0)
    csv = write_csv(folder / "ur5.csv", arm.joint_names, t, Q, QD, tau)
    out, printed = folder / "identified.yaml", io.StringIO()
    arguments = [str(csv), "--out", str(out), "--params-file", described(folder), "--quiet", "-p", "payload.mass:=0.0"]
    with contextlib.redirect_stdout(printed):
        assert identify_tool.main(arguments) == 0
    return out, folder / "identified.urdf", printed.getvalue()


def test_identify_writes_a_params_file_and_a_urdf_that_load_back(identified):
    parameters, urdf, printed = identified
    assert f"wrote {urdf}" in printed and "WARNING" not in printed
    from_parameters = load_model(parameters)
    from_urdf = load_urdf(urdf.read_text()).model
    pi, pi_urdf = inertial_parameters(from_parameters), inertial_parameters(from_urdf)
    n = from_parameters.n
    links = slice(0, 10 * n)
    friction = np.concatenate([pi[10 * n + 3 * i : 10 * n + 3 * i + 2] for i in range(n)])
    friction_urdf = np.concatenate([pi_urdf[10 * n + 3 * i : 10 * n + 3 * i + 2] for i in range(n)])
    assert np.abs(pi_urdf[links] - pi[links]).max() <= 1e-12 * np.abs(pi[links]).max()
    assert np.abs(friction_urdf - friction).max() <= 1e-12 * np.abs(friction).max()
    assert from_urdf.joint_names == from_parameters.joint_names == true_ur5().joint_names
    assert pi[10 * n + 2 :: 3].max() > 0  # armature: in the parameters (URDF has no place for it)


def test_identify_refuses_a_bad_urdf_in_one_line_and_writes_nothing(tmp_path, capsys):
    out, recording = tmp_path / "out.yaml", tmp_path / "x.csv"
    recording.write_text("t,q_1\n")  # the recording exists: the URDF is what is refused (every input checked first)
    assert (
        identify_tool.main([str(recording), "--out", str(out), "--urdf", str(tmp_path / "none.urdf"), "--quiet"]) == 1
    )
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "none.urdf: no such file" in error and not out.exists()


BLOCK_ROS = """
import sys
class NoRos:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("rclpy", "rosidl_runtime_py", "std_msgs", "sensor_msgs"):
            raise ImportError(f"{name} blocked: ROS is not installed")
sys.meta_path.insert(0, NoRos())
from irb140_dynamics.tools import excitation, identify, export_urdf
import irb140_dynamics.core, irb140_dynamics.identification.pipeline
code = export_urdf.main(["export_urdf", "--urdf", sys.argv[1], "--base", "base_link", "--tip", "tool0"])
assert "rclpy" not in sys.modules
sys.exit(code)
"""


def test_the_offline_tools_run_without_ros():
    done = subprocess.run(
        [sys.executable, "-c", BLOCK_ROS, str(UR5_URDF)], cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    model = load_urdf(done.stdout).model
    assert model.joint_names == true_ur5().joint_names


def test_the_names_a_tool_knows_follow_the_arm(tmp_path, capsys):
    """A URDF arm's own joints take limits, friction and armature (and the nodes' per-joint
    parameters); the IRB-140's joint names are unknown there; a sibling's name is known."""
    from irb140_dynamics.tools import export_urdf

    urdf = ["--urdf", str(UR5_URDF), "--base", BASE, "--tip", TIP, "--out", str(tmp_path / "a.urdf")]
    known = ["shoulder_pan_joint.armature:=0.1", "shoulder_pan_joint.kp:=10.0", "qos.depth:=5", "payload.mass:=1.0"]
    assert export_urdf.main(["export_urdf", *urdf, *(f"-p{text}" for text in known)]) == 0
    capsys.readouterr()
    assert export_urdf.main(["export_urdf", *urdf, "-p", "joint_1.armature:=0.1"]) == 2
    error = capsys.readouterr().err
    assert "-p: joint_1.armature (the arm has no joint joint_1; did you mean" in error and error.count("\n") == 1
    assert export_urdf.main(["export_urdf", *urdf, "-p", "shoulder_pan_joint.dh:=[0,0,0,0]"]) == 2
    assert "shoulder_pan_joint.dh" in capsys.readouterr().err  # a URDF's joints take no DH row
