"""A JointTrajectory file is read as YAML reads it: the points exactly as joint_trajectory_text
writes them without YAML's constructor, anything else by YAML itself."""

import numpy as np
import pytest
import yaml

from irb140_dynamics.core.io.trajectory_file import _as_written, joint_trajectory_text, read_joint_trajectory

LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
AWKWARD = [0.0, -0.0, 0.1, -123.456, 1e-300, 5e-324, 1.7976931348623157e308, -2.5e-7, 1e20, 3.0]


def yaml_reads(text: str):
    return next((d for d in yaml.load_all(text, Loader=LOADER) if d is not None), None)


def written() -> str:
    Q = np.array(AWKWARD).reshape(5, 2)
    return joint_trajectory_text(["a", "b"], [0.0, 0.05, 1.25, 2.0000000001, 7.5], Q, -Q, Q[::-1], ["a comment"])


def test_the_points_as_written_are_read_as_yaml_reads_them(tmp_path):
    text = written()
    path = tmp_path / "motion.yaml"
    path.write_text(text)
    assert _as_written(text, LOADER) is not None  # taken without YAML's constructor
    read = read_joint_trajectory(path)
    assert repr(read) == repr(yaml_reads(text))  # repr: the sign of -0.0, the types (float, int), the order
    assert read["points"][1]["positions"] == AWKWARD[2:4] and read["points"][3]["time_from_start"] == {
        "sec": 2,
        "nanosec": 0,
    }


@pytest.mark.parametrize(
    "change",
    [
        lambda t: t.replace("0.1,", "1e5,", 1),  # YAML 1.1: a string
        lambda t: t.replace("sec: 1,", "sec: 010,", 1),  # YAML 1.1: octal 8
        lambda t: t + "# the end\n",
        lambda t: t + "---\njoint_names: [c]\n",  # a second document
        lambda t: t.replace("\n- {", "\n  - {"),  # indented
        lambda t: t.replace("points:\n", "points:\n\n", 1),
        lambda t: t.replace("positions: [", "positions: [ ", 1),
        lambda t: t.replace("points:\n", "other:\n", 1),
        lambda t: "joint_names: [a\n" + t.split("\n", 2)[2],  # bad YAML before the points: its error
    ],
)
def test_anything_else_is_read_by_yaml(tmp_path, change):
    text = change(written())
    assert text != written()
    path = tmp_path / "motion.yaml"
    path.write_text(text)
    assert _as_written(text, LOADER) is None
    try:
        expected = repr(yaml_reads(text))
    except yaml.YAMLError as error:
        with pytest.raises(ValueError, match=f"not YAML: {str(error).splitlines()[0]}"):
            read_joint_trajectory(path)
    else:
        assert repr(read_joint_trajectory(path)) == expected
