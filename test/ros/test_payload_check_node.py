"""payload_check_node in-process: ~/check, runtime payload changes, /diagnostics."""

import math
import re

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from irb140_dynamics.core import RigidBody, irb140, rnea, workspace_load
from irb140_dynamics.core.payload import analysis as analysis_module
from irb140_dynamics.nodes.payload_check_node import node as module
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode

from ..support.ros_harness import running

NAMES = [f"joint_{i}" for i in range(1, 7)]
STRETCHED = [0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0]
REPORT_6KG = [0.0, 290.765, 105.348, 0.0, 6.25594, 0.0]


def parse_report(text: str) -> dict:
    """The report's joint rows as numbers (None for '-' or 'none'), and its max payloads."""
    rows = {}
    for line in text.splitlines():
        fields = line.split()
        if fields and fields[0] in NAMES:
            now, limit, use, worst, worst_use = (_number(x) for x in fields[1:6])
            rows[fields[0]] = dict(now=now, limit=limit, use=use, worst=worst, worst_use=worst_use)
    here = re.search(r"max payload: ([\d.]+) kg \((\w+)\) here", text)
    everywhere = re.search(r"([\d.]+) kg \((\w+) at .*\) over the workspace", text)
    rows["here"] = (float(here.group(1)), here.group(2)) if here else None
    rows["workspace"] = (float(everywhere.group(1)), everywhere.group(2)) if everywhere else None
    return rows


def _number(text: str):
    return None if text in ("-", "none") else float(text.removeprefix("<=").rstrip("%"))  # <=: of a bound


@pytest.fixture
def node(monkeypatch):
    """The node on wall time: a stall of the test under load must not make its joint state
    stale (staleness is tested on simulated time, sim_node below)."""
    monkeypatch.setattr(module, "STALE_AFTER", 60.0)
    overrides = [Parameter("payload.mass", value=6.0), Parameter("diagnostics.period", value=0.0)]
    with running(PayloadCheckNode, parameter_overrides=overrides) as harness:
        harness.diagnostics = harness.listen(DiagnosticArray, "/diagnostics")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        harness.client = harness.probe.create_client(Trigger, "/payload_check_node/check")
        assert harness.client.wait_for_service(timeout_sec=10)
        yield harness


def at_pose(harness, q, qd=()):
    harness.node.state = None
    harness.joint_states.publish(JointState(name=NAMES, position=list(q), velocity=list(qd)))
    assert harness.spin_until(lambda: harness.node.state is not None)


def check(harness):
    return harness.call(lambda: harness.client.call_async(Trigger.Request()))


def test_rated_payload_at_the_stretched_pose_uses_the_whole_limit(node):
    at_pose(node, STRETCHED)
    reply = check(node)
    assert reply.success, reply.message
    rows = parse_report(reply.message)
    np.testing.assert_allclose([rows[j]["now"] for j in NAMES], REPORT_6KG, atol=1e-3)
    for joint in ("joint_2", "joint_3", "joint_5"):
        assert rows[joint]["use"] == 100.0 and rows[joint]["limit"] == pytest.approx(rows[joint]["now"], abs=1e-3)
    assert rows["joint_1"]["limit"] is None and rows["joint_6"]["limit"] is None
    assert rows["here"] == (6.0, "joint_2") and rows["workspace"] == (6.0, "joint_2")


def test_a_heavier_payload_fails_and_names_the_limiting_joint(node):
    at_pose(node, STRETCHED)
    assert [r.successful for r in node.set_parameters([Parameter("payload.mass", value=7.0)])] == [True]
    reply = check(node)
    assert not reply.success
    verdict = reply.message.splitlines()[0]
    assert verdict.startswith("OVER-LIMIT: 7.000 kg does not fit: ") and "joint_2" in verdict
    assert parse_report(reply.message)["workspace"][1] == "joint_2"


@pytest.mark.parametrize(
    "com, q",
    [
        ([0.0, 0.0, 0.1], [0.3, -1.2, 1.0, 0.4, 0.9, -0.2]),
        ([0.08, -0.05, 0.04], [0.0, -0.5, 2.0, 1.0, -1.2, 0.7]),
        ([0.0, 0.15, 0.0], STRETCHED),
    ],
)
def test_max_payload_here_puts_the_limiting_joint_at_its_limit(node, com, q):
    assert all(r.successful for r in node.set_parameters([Parameter("payload.com", value=com)]))
    at_pose(node, q)
    rows = parse_report(check(node).message)
    mass, joint = rows["here"]
    j = NAMES.index(joint)
    limit = node.node.settings.analysis.limits.values[j]
    tau = rnea(irb140(payload=RigidBody(mass, tuple(com))), q, np.zeros(6), np.zeros(6))
    assert abs(tau[j]) == pytest.approx(limit, rel=2e-3 / mass)  # the reply prints mass to 1 g
    exact = node.node.check()[0].max_payload_here.mass
    tau = rnea(irb140(payload=RigidBody(exact, tuple(com))), q, np.zeros(6), np.zeros(6))
    assert abs(tau[j]) == pytest.approx(limit, rel=1e-9)


def test_runtime_payload_change_changes_the_next_check(node):
    at_pose(node, STRETCHED)
    before = parse_report(check(node).message)
    assert all(
        r.successful
        for r in node.set_parameters(
            [Parameter("payload.mass", value=2.0), Parameter("payload.com", value=[0.0, 0.0, 0.2])]
        )
    )
    after = parse_report(check(node).message)
    expected = rnea(irb140(payload=RigidBody(2.0, (0.0, 0.0, 0.2))), STRETCHED, np.zeros(6), np.zeros(6))
    np.testing.assert_allclose([after[j]["now"] for j in NAMES], expected, atol=1e-3)
    assert after["joint_2"]["now"] != before["joint_2"]["now"]


@pytest.mark.parametrize(
    "parameter, reason",
    [
        (Parameter("payload.mass", value=-1.0), "payload.mass"),
        (Parameter("payload.com", value=[0.0, math.nan, 0.0]), "payload.com: must be finite"),
        (Parameter("payload.inertia", value=[0.1, 0.1, 0.5, 0.0, 0.0, 0.0]), "payload.inertia"),
        (Parameter("rated_payload.mass", value=-6.0), "rated_payload.mass"),
    ],
)
def test_invalid_payload_is_refused_and_the_old_one_kept(node, parameter, reason):
    at_pose(node, STRETCHED)
    before = check(node).message
    [result] = node.set_parameters([parameter])
    assert not result.successful and reason in result.reason
    assert check(node).message == before


def test_diagnostics_carry_the_figures_of_the_reply(node):
    at_pose(node, [0.2, -1.0, 1.3, 0.5, 0.8, 0.1], qd=[0.1, 0.2, -0.3, 0.0, 0.5, 0.0])
    count = len(node.diagnostics)
    reply = check(node)
    assert node.spin_until(lambda: len(node.diagnostics) > count)
    rows = parse_report(reply.message)
    statuses = {s.name.split(": ", 1)[1]: s for s in node.diagnostics[-1].status}
    assert set(statuses) == set(NAMES) | {"payload", "payload estimation"}
    for joint in NAMES:
        values = {kv.key: kv.value for kv in statuses[joint].values}
        row = rows[joint]
        assert float(values["torque now [N m]"]) == row["now"]
        assert float(values["worst static torque [N m]"]) == row["worst"]
        assert _number(values["limit [N m]"]) == row["limit"]
        assert _number(values["use now"]) == row["use"]
        assert _number(values["worst use"]) == row["worst_use"]
    levels = {joint: statuses[joint].level for joint in NAMES}
    assert levels["joint_1"] == DiagnosticStatus.OK and levels["joint_2"] == DiagnosticStatus.WARN  # 100 % >= 90 %
    summary = {kv.key: kv.value for kv in statuses["payload"].values}
    assert (float(summary["max payload here [kg]"]), summary["max payload here: limited by"]) == rows["here"]
    assert (
        float(summary["max payload over the workspace [kg]"]),
        summary["max payload over the workspace: limited by"],
    ) == rows["workspace"]


def test_without_joint_states_it_checks_the_workspace_only(node):
    reply = check(node)
    assert reply.success
    assert "workspace only" in reply.message
    assert parse_report(reply.message)["here"] is None


def statuses_after(harness, trigger) -> tuple:
    """(trigger(), the /diagnostics statuses it published by joint or "payload")."""
    count = len(harness.diagnostics)
    result = trigger()
    assert harness.spin_until(lambda: len(harness.diagnostics) > count)
    return result, {s.name.split(": ", 1)[1]: s for s in harness.diagnostics[-1].status}


def test_a_payload_loading_a_joint_without_limit_is_noted_and_warned(node):
    """3 kg 0.1 m off the flange axis loads joint 6, which the rated payload does not."""
    assert all(
        r.successful
        for r in node.set_parameters(
            [Parameter("payload.mass", value=3.0), Parameter("payload.com", value=[0.1, 0.0, 0.0])]
        )
    )
    at_pose(node, [0.3, -1.0, 1.2, 0.5, 0.2, 0.1])  # after the change (its proof takes a while): fresh
    reply, statuses = statuses_after(node, lambda: check(node))
    assert reply.success, reply.message  # the limits decide
    notes = [line for line in reply.message.splitlines() if line.startswith("note:")]
    assert notes == [
        "note: joint_6 has no limit, yet this payload loads it (2.943 N m in its worst pose): set joint_6.torque_limit"
    ]
    assert "joint_1, joint_6: none: the rated payload cannot load it" in reply.message
    assert statuses["joint_6"].level == DiagnosticStatus.WARN
    assert "set joint_6.torque_limit" in statuses["joint_6"].message
    assert statuses["joint_1"].level == DiagnosticStatus.OK
    assert statuses["joint_1"].message == "none: the rated payload cannot load it"
    assert statuses["payload"].level == DiagnosticStatus.WARN

    # given a limit, joint 6 is checked like the others
    assert all(r.successful for r in node.set_parameters([Parameter("joint_6.torque_limit", value=10.0)]))
    at_pose(node, [0.3, -1.0, 1.2, 0.5, 0.2, 0.1])
    reply, statuses = statuses_after(node, lambda: check(node))
    assert "note:" not in reply.message
    assert parse_report(reply.message)["joint_6"]["limit"] == 10.0
    assert statuses["joint_6"].level == DiagnosticStatus.OK


def test_a_failure_of_the_analysis_is_reported_and_the_next_change_recovers(node, monkeypatch):
    """The limits and the workspace analysis run once a change is accepted, off the
    executor: a failure there (a defect) keeps the previous settings, ~/check says it
    cannot check, and the next change is analysed once and in force."""
    at_pose(node, STRETCHED)
    settings = node.node.settings

    def failing(*args, **kwargs):
        raise ValueError("payload.com: the sweep failed")

    monkeypatch.setattr(analysis_module, "workspace_load", failing)
    assert [r.successful for r in node.set_parameters([Parameter("payload.mass", value=2.0)])] == [True]
    assert node.node.settings is settings
    reply = check(node)
    assert not reply.success
    assert reply.message == "UNPROVEN: cannot check: parameters accepted but not applied: payload.com: the sweep failed"

    built = []

    def sweep(*args):
        built.append(workspace_load(*args))
        return built[-1]

    monkeypatch.setattr(analysis_module, "workspace_load", sweep)
    assert [r.successful for r in node.set_parameters([Parameter("payload.mass", value=3.0)])] == [True]
    assert len(built) == 1 and node.node.settings.analysis.workspace is built[0]  # built once
    assert node.node.settings.model.payload.mass == 3.0
    reply = check(node)
    assert reply.success and reply.message.startswith("OK: 3.000 kg fits, worst joint_"), reply.message
    assert reply.message.splitlines()[1] == "payload 3.000 kg at (0.000, 0.000, 0.000) m"


def test_fresh_joint_states_carry_no_age_note(node):
    at_pose(node, STRETCHED)
    reply, statuses = statuses_after(node, lambda: check(node))
    assert "received" not in reply.message
    assert "stale" not in statuses["payload"].message


@pytest.fixture
def sim_node():
    """The node on simulated time, the probe publishing /clock."""
    overrides = [Parameter("use_sim_time", value=True), Parameter("diagnostics.period", value=0.0)]
    with running(PayloadCheckNode, parameter_overrides=overrides) as harness:
        harness.diagnostics = harness.listen(DiagnosticArray, "/diagnostics")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        harness.clock = harness.publisher(Clock, "/clock")
        harness.client = harness.probe.create_client(Trigger, "/payload_check_node/check")
        assert harness.client.wait_for_service(timeout_sec=10)
        yield harness


def set_time(harness, sec: int, nanosec: int = 0) -> None:
    harness.clock.publish(Clock(clock=Time(sec=sec, nanosec=nanosec)))
    stamp = sec * 10**9 + nanosec
    assert harness.spin_until(lambda: harness.node.get_clock().now().nanoseconds == stamp)


def test_an_old_joint_state_is_used_and_reported_stale(sim_node):
    set_time(sim_node, 100)
    at_pose(sim_node, STRETCHED)
    set_time(sim_node, 100, 900_000_000)  # 0.9 s: fresh enough
    reply, statuses = statuses_after(sim_node, lambda: check(sim_node))
    assert "received" not in reply.message and statuses["payload"].level == DiagnosticStatus.OK

    set_time(sim_node, 112, 300_000_000)
    reply, statuses = statuses_after(sim_node, lambda: check(sim_node))
    assert reply.message.splitlines()[-1] == "note: joint_states received 12.3 s ago"
    assert parse_report(reply.message)["joint_2"]["now"] == pytest.approx(243.382, abs=1e-3)  # that state, no payload
    summary = statuses["payload"]
    assert summary.level == DiagnosticStatus.WARN and "stale joint_states" in summary.message
    assert {kv.key: kv.value for kv in summary.values}["stale joint_states"] == "joint_states received 12.3 s ago"
