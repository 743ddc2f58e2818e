"""The tools' --hold (tools.common.add_model_arguments, over model.held_positions): load_diagram
checks a payload with the rest of the tree where told (test_held_positions' LIMITED: 15 kg
beyond the torso's limit with the other arm at zero, within it with the arm turned); a bad
held position refused in one line naming the option, exit status 2, nothing printed."""

import pytest

from irb140_dynamics.tools import load_diagram

from ..core.test_held_positions import LIMITED
from ..core.test_urdf_trees import TWO_ARMS
from ..support.paths import URDF_DATA


def run_check(capsys, tmp_path, *args, text=LIMITED, mass="15"):
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(text)
    status = load_diagram.main(["--urdf", str(urdf), "--check", mass, "0", "0", *args])
    out, err = capsys.readouterr()
    return status, out, err


def test_load_diagram_checks_a_payload_with_the_rest_of_the_tree_where_told(tmp_path, capsys):
    assert run_check(capsys, tmp_path, "--tip", "la2")[0] == 1  # 15 kg: beyond the torso, the other arm at zero
    status, out, err = run_check(capsys, tmp_path, "--tip", "la2", "--hold", "r2=1.2")
    assert status == 0 and "inside" in out and "limiting joint torso" in out, (out, err)


@pytest.mark.parametrize(
    "args, message",
    [
        (["--hold", "r_1=0.1"], "--hold r_1=0.1: the URDF has no joint 'r_1'; did you mean r1?"),
        (["--hold", "l1=0.2"], "--hold l1=0.2: a joint of the model, not held"),
        (["--hold", "finger_a=0.1"], "--hold finger_a=0.1: a mimic joint: it follows 'r2'"),
        (["--hold", "r1=5"], "--hold r1=5: 5 rad is outside its limits [-2, 2] rad"),
        (["--hold", "r2=-2"], "--hold r2=-2: -3.8 rad for mimic joint 'finger_a' is outside its limits [-2, 2] rad"),
        (["--hold", "r1=nan"], "--hold r1=nan: expected JOINT=VALUE, the value a finite number"),
        (["--hold", "r1"], "--hold r1: expected JOINT=VALUE"),
        (["--hold", "bracket=0"], "--hold bracket=0: a fixed joint"),
        (["--hold", "r1=0.1", "--hold", "r1=0.2"], "--hold r1=0.2: r1 is given twice"),
        (["-p", "model.held_positions:=[r1=inf]"], "model.held_positions r1=inf: expected JOINT=VALUE"),
        (["-p", "model.held_positions:=r1=0.1"], "model.held_positions: expected a list of 'JOINT=VALUE' texts"),
    ],
)
def test_a_bad_held_position_is_refused_in_one_line_naming_the_option(args, message, tmp_path, capsys):
    status, out, err = run_check(capsys, tmp_path, "--tip", "la2", *args, text=TWO_ARMS, mass="1")
    assert (status, out, err.count("\n")) == (2, "", 1) and message in err, err


def test_holding_without_a_urdf_or_a_joint_a_chain_lacks_is_refused(tmp_path, capsys):
    status = load_diagram.main(["--check", "1", "0", "0", "--hold", "joint_1=0.1"])
    _, err = capsys.readouterr()
    assert status == 2 and "--hold holds joints of a URDF: give --urdf" in err and err.count("\n") == 1
    status = load_diagram.main(["--check", "1", "0", "0", "-p", "model.held_positions:=[joint_1=0.1]"])
    _, err = capsys.readouterr()  # the core's line (a node's words: model.urdf_file) in the tool's
    assert status == 2 and "model.held_positions holds joints of a URDF: give --urdf, or model.source" in err, err
    chain = (URDF_DATA / "ur5.urdf").read_text()  # one chain: nothing off it to hold
    status, out, err = run_check(capsys, tmp_path, "--hold", "elbow_jont=0.1", text=chain, mass="1")
    assert status == 2 and "--hold elbow_jont=0.1: the URDF has no joint 'elbow_jont'; did you mean elbow_joint?" in err


def test_a_chain_whose_joint_a_gripper_follows_says_where_to_end_it(tmp_path, capsys):
    """TWO_ARMS to ra2: its fingers follow r2 (mimic joints of the model, off the chain): the
    load diagram takes a chain without them and says so, naming the joint to end above and
    hold; ending there (ra1), the fingers follow the r2 held."""
    status, out, err = run_check(capsys, tmp_path, "--tip", "ra2", text=TWO_ARMS, mass="1")
    assert (status, out, err.count("\n")) == (2, "", 1), err  # bad input to a check: 2 (1 is its answer: outside)
    assert "takes a chain without mimic joints: 'finger_b' follows 'r2'" in err
    assert err.rstrip().endswith("end the chain above 'r2' (--tip LINK) and hold it (--hold r2=VALUE)"), err
    status, out, err = run_check(capsys, tmp_path, "--tip", "ra1", "--hold", "r2=0.3", text=TWO_ARMS, mass="1")
    assert status == 0 and "inside" in out, (out, err)


def test_the_advice_to_end_the_chain_is_whole_for_long_joint_names(tmp_path, capsys):
    """Long names (vendors' grippers) are cut where they are named, never the advice."""
    leader, follower = "gripper_left_finger_joint_" + "x" * 40, "gripper_left_outer_finger_left_joint_" + "y" * 40
    text = TWO_ARMS.replace('"r2"', f'"{leader}"').replace('"finger_b"', f'"{follower}"')
    status, out, err = run_check(capsys, tmp_path, "--tip", "ra2", text=text, mass="1")
    assert status == 2 and err.count("\n") == 1 and len(err) < 300, err
    assert err.rstrip().endswith(f"(--tip LINK) and hold it (--hold {leader}=VALUE)"), err
