"""The payload check as the service returns it: the verdict line first, then the report's
text and columns, its rows the figures /diagnostics carries, the notes."""

import re

import pytest

from irb140_dynamics.core import RigidBody
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.core.payload import check_payload, workspace_load

from ..support.urdf_support import URDF_DATA
from .test_payload import STATES, STRETCHED


def test_report_text(model, limits):
    check = check_payload(model, RigidBody(6.0), limits, q=STRETCHED)
    text = check.report()
    lines = text.splitlines()
    # joints 2, 3 and 5 at their limits (derived from this payload): one of the ties, to rounding
    assert re.fullmatch(r"OK: 6\.000 kg fits, worst joint_[235] at 100\.0 % of its limit", lines[0])
    assert lines[1] == "payload 6.000 kg at (0.000, 0.000, 0.000) m"
    assert lines[4].split()[:6] == ["joint_2", "290.765", "290.765", "100.0%", "290.765", "100.0%"]
    assert lines[4].endswith("  (0, -90, 90, 0, 0, 0)")
    assert lines[3].split()[:3] == ["joint_1", "0.000", "none"]
    assert lines[-2] == (
        "max payload: 6.000 kg (joint_2) here, 6.000 kg (joint_2 at (0, -90, 90, 0, 0, 0) deg) over the workspace"
    )
    assert re.fullmatch(r"proof: the worst static torques are exact to [\d.e+-]+ N m", lines[-1])
    assert float(lines[-1].split()[-3]) <= 1e-9 * 290.765
    print(text)


def test_workspace_part_alone_and_reused(model, limits):
    load = workspace_load(model, RigidBody(6.0), limits)
    check = check_payload(model, RigidBody(6.0), limits, q=STRETCHED, workspace=load)
    assert check.workspace is load
    no_state = check_payload(model, RigidBody(6.0), limits, workspace=load)
    assert no_state.torque is None and no_state.ok
    assert "-" in no_state.report().splitlines()[4].split()[1]


def test_report_rows_are_the_figures(model, limits, quick_proofs):
    """One source: each report row is its joint's figures, the summary the payload's."""
    check = check_payload(model, RigidBody(2.0, (0.0, 0.05, 0.1)), limits, q=STATES[1][0], qd=STATES[1][1])
    lines = check.report().splitlines()
    for j in range(6):
        figures = check.joint_figures(j)
        assert list(figures) == [
            "torque now [N m]",
            "limit [N m]",
            "use now",
            "worst static torque [N m]",
            "worst use",
            "worst pose [deg]",
            "limit source",
            "worst static bound [N m]",
            "worst static gap [N m]",
        ]
        assert float(figures["worst static gap [N m]"]) == pytest.approx(check.workspace.gap[j], rel=0.05, abs=1e-300)
        row = lines[3 + j]
        assert row.split()[1:6] == list(figures.values())[:5]
        assert row.endswith("  " + figures["worst pose [deg]"])
        assert figures["limit source"] in lines[9]
    payload = check.payload_figures()
    assert lines[0] == check.headline()
    assert lines[1] == f"payload {payload['payload mass [kg]']} kg at {payload['payload com [m]']} m"
    here = f"{payload['max payload here [kg]']} kg ({payload['max payload here: limited by']}) here"
    everywhere = (
        f"{payload['max payload over the workspace [kg]']} kg "
        f"({payload['max payload over the workspace: limited by']} at "
        f"{payload['max payload over the workspace: pose [deg]']} deg) over the workspace"
    )
    assert lines[10] == f"max payload: {here}, {everywhere}"


def test_a_payload_loading_a_joint_without_limit_gets_a_note(model, limits):
    """3 kg 0.1 m off the flange axis turns joint 6, which the rated payload never loads."""
    check = check_payload(model, RigidBody(3.0, (0.1, 0.0, 0.0)), limits, q=STATES[1][0])
    assert limits.reason(5) == "none: the rated payload cannot load it"
    assert abs(check.workspace.torque[5]) == pytest.approx(3.0 * 9.81 * 0.1, rel=1e-9)
    assert check.loaded_without_limit == [5]  # not joint 1: a payload never turns it statically
    assert check.ok  # the limits decide, the note only warns
    assert check.report().splitlines()[-1] == (
        "note: joint_6 has no limit, yet this payload loads it (2.943 N m in its worst pose): set joint_6.torque_limit"
    )
    centred = check_payload(model, RigidBody(6.0), limits, q=STRETCHED)
    assert centred.loaded_without_limit == [] and "note" not in centred.report()


def test_report_columns_stay_apart_at_any_use(model, limits):
    """Uses of 1,000 % and more keep at least two spaces between the columns, aligned
    (never run together as in "243.382        1.00024338.2%")."""
    check = check_payload(model, RigidBody(600.0), limits, q=STRETCHED)
    rows = check.report().splitlines()[2:9]
    for j, line in enumerate(rows[1:]):
        cells = [cell.strip() for cell in line.split("  ") if cell.strip()]
        assert cells[1:6] == list(check.joint_figures(j).values())[:5] and len(cells) == 7, line
    assert float(rows[2].split()[3].rstrip("%")) > 1000  # joint_2 now
    assert len({len(line.split("  (")[0]) for line in rows[1:]}) == 1  # the pose column aligned


def test_a_prismatic_joints_position_is_shown_in_metres():
    """The worst poses and the largest payload's pose show a prismatic joint's position in
    m, the revolute joints' angles in degrees. The payload, on the wrist's axis, loads no
    joint of this arm (a vertical turn, a level slide): its largest mass is unbounded, not
    what rounding noise would allow."""
    model = load_urdf((URDF_DATA / "prismatic_arm.urdf").read_text()).model
    slide = next(j for j, joint in enumerate(model.joints) if joint.prismatic)
    check = check_payload(model, RigidBody(1.0, (0.0, 0.0, 0.05)), q=[0.1] * model.n)
    figures = check.joint_figures(slide)
    shown = figures["worst pose [deg]"].strip("()").split(", ")
    assert shown[slide] == f"{check.workspace.pose[slide][slide]:.3f} m"
    assert all(not entry.endswith(" m") for k, entry in enumerate(shown) if k != slide)
    assert re.search(r"\d m[,)]", check.report())
    assert "max payload: unbounded here, unbounded over the workspace" in check.report()
