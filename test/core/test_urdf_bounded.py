"""URDF input is bounded: a size limit before parsing, binary data and device files
refused, no recursion in any walk of the tree (a 10,000-link chain loads or is refused
in one line), every refusal one line under 300 characters; and a seeded, bounded fuzz
of ``load_urdf`` (200 cases; the longer run: bench/fuzz_urdf.py)."""

import os
import sys

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from irb140_dynamics.core.urdf import MAX_JOINTS, UrdfError, load_urdf, read_urdf

from ..support.urdf_mutations import KINDS, SEED_TEXT, mutated, outcome

LINK = '<link name="l{i}"><inertial><mass value="0.001"/><inertia ixx="1e-6" iyy="1e-6" izz="1e-6"/></inertial></link>'
JOINT = (
    '<joint name="j{i}" type="{kind}"><parent link="l{parent}"/><child link="l{i}"/><origin xyz="0 0 0.01"/>'
    '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
)


def long_chain(links: int, moving_every: int) -> str:
    parts = ['<robot name="long">', LINK.format(i=0)]
    for i in range(1, links + 1):
        kind = "revolute" if i % moving_every == 0 else "fixed"
        parts += [JOINT.format(i=i, parent=i - 1, kind=kind), LINK.format(i=i)]
    return "".join(parts + ["</robot>"])


def refusal(text, **kwargs) -> str:
    with pytest.raises(UrdfError) as refused:
        load_urdf(text, **kwargs)
    line = str(refused.value)
    assert "\n" not in line and len(line) < 300, line
    return line


def test_the_seed_text_loads():
    loaded = load_urdf(SEED_TEXT, "base", "tool0")
    # the finger off the chain follows j3: a mimic joint of the model, hanging off the chain's last link
    assert [j.kind for j in loaded.model.joints] == ["revolute", "prismatic", "revolute", "prismatic"]
    assert loaded.model.joint_names == ("j1", "slide-2", "j3") and loaded.model.parent == (-1, 0, 1, 2)
    assert loaded.held_joints == ()
    assert outcome(SEED_TEXT, {"base_link": "base", "tip_link": "tool0"}) == "loaded"


@pytest.mark.slow
def test_a_10000_link_chain_loads_without_recursion():
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(200)  # a recursive walk would fail at once
    try:
        loaded = load_urdf(long_chain(10_000, 500))
    finally:
        sys.setrecursionlimit(limit)
    assert loaded.model.n == 20 and loaded.tip_link == "l10000"


def test_more_moving_joints_than_the_limit_are_refused_in_one_line():
    line = refusal(long_chain(10_000, 1))
    assert f"10000 moving joints from 'l0' to 'l10000', more than the limit of {MAX_JOINTS}" in line
    assert "max_joints" not in line and "load part of it" in line  # the limit and what to do, no argument name
    assert load_urdf(long_chain(120, 1), max_joints=120).model.n == 120


def test_text_over_the_size_limit_is_refused_before_parsing():
    text = SEED_TEXT + " " * 1000
    assert "more than the limit of 1000 (the environment's IRB140_MAX_FILE_BYTES sets it)" in refusal(
        text, max_chars=1000
    )
    assert "more than the limit" in refusal("<" * 10, max_chars=5)  # not parsed: no XML error


@pytest.mark.parametrize(
    "text, message",
    [
        ("\x00" * 64, "binary data, not text (character 0x00 at 0)"),
        (SEED_TEXT.replace('<link name="l1">', '<link name="l1">\x07'), "binary data"),
        (b"<robot/>", "bytes given, not text"),
        ("<robot>" + "<a>" * 100_000 + "</a>" * 100_000 + "</robot>", "no <link>"),
        (
            '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">'
            + "".join(f'<!ENTITY a{i} "{("&a;" if i == 0 else f"&a{i - 1};") * 10}">' for i in range(8))
            + ']><robot name="&a7;"><link name="l"/></robot>',
            "URDF XML: does not parse",
        ),
    ],
)
def test_binary_deep_and_exploding_input_is_refused_in_one_line(text, message):
    assert message in refusal(text)


@pytest.mark.parametrize("path", ["/dev/zero", "/dev/urandom"])
def test_device_files_are_refused_in_one_line(path):
    if not os.path.exists(path):
        pytest.skip(f"no {path}")
    with pytest.raises(UrdfError, match="not a regular file"):
        read_urdf(path)


def test_read_urdf_bounds_a_file(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(SEED_TEXT)
    assert read_urdf(path) == SEED_TEXT
    with pytest.raises(UrdfError, match="over the 100-byte limit"):
        read_urdf(path, max_chars=100)
    path.write_bytes(b"\x7fELF\x00\x01")
    with pytest.raises(UrdfError, match="binary data"):
        read_urdf(path)
    path.write_bytes(b"<robot name='\xff'/>")
    with pytest.raises(UrdfError, match="not UTF-8 text"):
        read_urdf(path)


def test_long_names_and_long_lists_stay_within_a_line():
    name = "x" * 5000
    assert len(refusal(SEED_TEXT, base_link=name)) < 300
    many = SEED_TEXT.replace("</robot>", "".join(f'<link name="{name}{i}"/>' for i in range(50)) + "</robot>")
    assert "51 root links" in refusal(many)


EDITS = st.lists(st.tuples(st.sampled_from(KINDS), st.floats(0, 0.999), st.integers(0, 1000)), min_size=1, max_size=4)


@pytest.mark.slow
@settings(max_examples=200, derandomize=True, deadline=None, suppress_health_check=list(HealthCheck))
@given(EDITS, st.booleans())
def test_fuzz_load_urdf(edits, with_ends):
    """Whatever the edits, the loader loads a model that computes, or refuses in one line."""
    ends = {"base_link": "base", "tip_link": "tool0"} if with_ends else {}
    assert not outcome(mutated(SEED_TEXT, edits), ends).startswith("defect"), (edits, with_ends)
