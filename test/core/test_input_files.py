"""Input files are checked before they are parsed: one line naming the file and why."""

import pytest

from irb140_dynamics.core.io.params_file import rcl_refusal, read_parameter_file
from irb140_dynamics.core.io.text_files import ENVIRONMENT_LIMIT, read_text_file

from ..support.paths import CONFIG


def test_the_shipped_parameter_file_reads():
    params = read_parameter_file(CONFIG)
    assert params["joint_names"][0] == "joint_1"


@pytest.mark.parametrize(
    "make, reason",
    [
        (lambda tmp: tmp / "missing.yaml", "no such parameter file"),
        (lambda tmp: tmp, "is a folder"),
        (lambda tmp: "/dev/zero", "not a regular file"),
        (lambda tmp: _write(tmp / "nul.yaml", b"a: 1\0"), "binary data"),
        (lambda tmp: _write(tmp / "latin.yaml", b"a: \xe9\xff"), "not UTF-8"),
        (lambda tmp: _write(tmp / "alias.yaml", b"/**:\n  ros__parameters:\n    a: &x [1]\n    b: *x\n"), "aliases"),
        (lambda tmp: _write(tmp / "deep.yaml", b"a: " + b"[" * 5000 + b"]" * 5000), "nested too deeply"),
        (lambda tmp: _write(tmp / "bad.yaml", b"a: [1, 2\n"), "not valid YAML"),
        (lambda tmp: _write(tmp / "list.yaml", b"- 1\n- 2\n"), "not a parameter file"),
        (lambda tmp: _write(tmp / "section.yaml", b"/**: 3\n"), "ros__parameters"),
    ],
)
def test_bad_parameter_files_are_refused_in_one_line(tmp_path, make, reason):
    path = make(tmp_path)
    with pytest.raises(ValueError) as error:
        read_parameter_file(path)
    text = str(error.value)
    assert reason in text and str(path) in text
    assert "\n" not in text and len(text) < 300


def test_the_size_limit_is_checked_before_reading_and_can_be_changed(tmp_path, monkeypatch):
    path = _write(tmp_path / "big.yaml", b"#" * 2000)
    monkeypatch.setenv(ENVIRONMENT_LIMIT, "1000")
    with pytest.raises(ValueError, match="over the 1,000-byte limit"):
        read_text_file(path, "parameter file")
    monkeypatch.setenv(ENVIRONMENT_LIMIT, "4000")
    assert read_text_file(path, "parameter file") == "#" * 2000


def _write(path, data: bytes):
    path.write_bytes(data)
    return path


RCL_AT = ", at /project/src/parse.c:391, at /project/src/rcl/arguments.c:415"  # rcl's source lines, as it appends them


def test_rcl_refusing_a_params_file_is_one_line_quoting_the_line(tmp_path):
    """rcl's text (as rclpy.init raises it, Jazzy) read back: the file, the line number, the
    line itself, and the hint for a list of mixed integers and doubles."""
    path = tmp_path / "mixed.yaml"
    path.write_text("/**:\n  ros__parameters:\n    gravity: [0, 0.0, -9.81]\n")
    text = (
        f"failed to initialize rcl: Couldn't parse params file: '--params-file {path}'. Error: Sequence should be "
        f"of same type. Value type 'double' do not belong at line_num 3{RCL_AT}"
    )
    assert rcl_refusal(text) == (
        f"{path}:3: Sequence should be of same type. Value type 'double' do not belong in "
        "`gravity: [0, 0.0, -9.81]`; write every number of a list as a double, e.g. 0.0 not 0"
    )
    near = f"failed to initialize rcl: Couldn't parse params file: '--params-file {path}'. Error: Error parsing a event near line 0{RCL_AT}"
    assert rcl_refusal(near) == f"{path}: Error parsing a event"  # line 0: no line to quote
    assert rcl_refusal(f"failed to initialize rcl: no such thing{RCL_AT}") == "failed to initialize rcl: no such thing"
