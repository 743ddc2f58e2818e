"""Parameter changes: checked whole within the call, built off the executor, the message flow
never waiting for a build; undeclared names refused by name."""

import threading

import numpy as np
import pytest
from rcl_interfaces.msg import Parameter as ParameterMsg
from rcl_interfaces.msg import ParameterValue
from rcl_interfaces.srv import SetParameters, SetParametersAtomically
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from irb140_dynamics.core import RigidBody, gravity, irb140
from irb140_dynamics.core.payload import analysis as payload_analysis
from irb140_dynamics.core.trajectories import stream_settings as id_settings
from irb140_dynamics.nodes.id_node import node as id_module
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.payload_check_node import node as payload_module
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode

from ..support.ros_harness import TIMEOUT, running

NAMES = [f"joint_{i}" for i in range(1, 7)]
Q = [0.1, -0.8, 1.0, 0.2, 0.5, 0.0]


class Gate:
    """Wraps a function so that, once closed, calls wait until the gate opens again."""

    def __init__(self, function):
        self.function, self.calls = function, 0
        self._open = threading.Event()
        self._open.set()

    def close(self):
        self._open.clear()

    def open(self):
        self._open.set()

    def __call__(self, *args, **kwargs):
        self.calls += 1
        assert self._open.wait(TIMEOUT), "the gate stayed closed"
        return self.function(*args, **kwargs)


def unsettled_set(harness, params):
    """SetParameters through the service, not waiting for the change to be in force."""
    client = harness.parameter_client()
    return harness.call(lambda: client.set_parameters(params)).results


@pytest.fixture
def gated_id_node(monkeypatch):
    """id_node whose builds (always off the executor) wait at a gate."""
    gate = Gate(id_module.finish_settings)
    monkeypatch.setattr(id_module, "finish_settings", gate)
    with running(IdNode) as harness:
        harness.gate = gate
        harness.gravity = harness.listen(JointState, "gravity_torques")
        harness.joint_states = harness.publisher(JointState, "joint_states")
        yield harness
        gate.open()


def gravity_now(harness):
    count = len(harness.gravity)
    harness.joint_states.publish(JointState(name=NAMES, position=Q))
    assert harness.spin_until(lambda: len(harness.gravity) > count)
    return harness.gravity[-1].effort


def test_messages_flow_while_a_change_is_built(gated_id_node):
    node = gated_id_node
    node.gate.close()
    assert [r.successful for r in unsettled_set(node, [Parameter("payload.mass", value=5.0)])] == [True]
    assert node.node.rebuild.status().startswith("new parameters being applied")
    for _ in range(3):  # answered meanwhile, by the model before the change
        np.testing.assert_allclose(gravity_now(node), gravity(irb140(), Q), rtol=1e-12, atol=1e-12)
    node.gate.open()
    node.settle()
    assert node.node.rebuild.status() is None
    np.testing.assert_allclose(gravity_now(node), gravity(irb140(payload=RigidBody(5.0)), Q), rtol=1e-12, atol=1e-12)


def test_changes_faster_than_builds_end_with_the_newest(gated_id_node):
    node = gated_id_node
    node.gate.close()
    calls = node.gate.calls
    for mass in (1.0, 2.0, 3.0, 4.0, 5.0):
        assert node.node.set_parameters([Parameter("payload.mass", value=mass)])[0].successful
    node.gate.open()
    node.settle()
    assert node.node.settings.model.payload.mass == 5.0
    assert node.gate.calls - calls <= 2  # the one under way, then the newest
    np.testing.assert_allclose(gravity_now(node), gravity(irb140(payload=RigidBody(5.0)), Q), rtol=1e-12, atol=1e-12)


def test_a_payload_or_gravity_change_compiles_nothing_and_keeps_or_derives_the_limits(monkeypatch):
    """The kernels take the payload and gravity as an argument: nothing to compile. A payload
    change leaves the markers' torque limits as they are; gravity changes them."""
    derived = Gate(id_settings.derive_torque_limits)
    monkeypatch.setattr(id_settings, "derive_torque_limits", derived)
    with running(IdNode) as harness:
        node = harness.node
        kernels, calls = node.settings.kernels, derived.calls
        assert node.set_parameters([Parameter("payload.mass", value=3.0)])[0].successful
        harness.settle()
        assert node.settings.model == irb140(payload=RigidBody(3.0)) and derived.calls == calls
        assert node.settings.kernels.native == kernels.native
        assert node.set_parameters([Parameter("gravity", value=[0.0, 0.0, -9.80665])])[0].successful
        harness.settle()
        assert derived.calls == calls + 1
        expected = irb140(payload=RigidBody(3.0)).with_gravity((0.0, 0.0, -9.80665))
        assert node.settings.model == expected


@pytest.fixture
def gated_payload_node(monkeypatch):
    gate = Gate(payload_analysis.workspace_load)
    monkeypatch.setattr(payload_analysis, "workspace_load", gate)
    overrides = [Parameter("diagnostics.period", value=0.0)]
    with running(PayloadCheckNode, parameter_overrides=overrides) as harness:
        harness.gate = gate
        harness.client = harness.probe.create_client(Trigger, "/payload_check_node/check")
        assert harness.client.wait_for_service(timeout_sec=TIMEOUT)
        yield harness
        gate.open()


def check(harness):
    return harness.call(lambda: harness.client.call_async(Trigger.Request()))


def test_check_right_after_a_change_waits_and_answers_for_the_new_parameters(gated_payload_node):
    """~/check is not answered "pending": the request is held until the analysis is in
    force, and the executor goes on serving the rest meanwhile."""
    node = gated_payload_node
    node.gate.close()
    assert [r.successful for r in unsettled_set(node, [Parameter("payload.mass", value=7.0)])] == [True]
    future = node.client.call_async(Trigger.Request())
    assert node.spin_until(lambda: node.node.check_service.held == 1)
    client = node.parameter_client()  # meanwhile: the parameter services answer, joint states are taken
    assert node.call(lambda: client.get_parameters(["payload.mass"])).values[0].double_value == 7.0
    node.publisher(JointState, "joint_states").publish(JointState(name=NAMES, position=Q))
    assert node.spin_until(lambda: node.node.state is not None)
    assert not future.done(), future.result()
    node.gate.open()
    assert node.spin_until(future.done)
    reply = future.result()
    assert not reply.success and reply.message.startswith("OVER-LIMIT: 7.000 kg does not fit: "), reply.message
    assert reply.message.splitlines()[1] == "payload 7.000 kg at (0.000, 0.000, 0.000) m"
    assert node.node.check_service.held == 0


def test_check_waits_at_most_check_wait_timeout(gated_payload_node):
    node = gated_payload_node
    assert node.set_parameters([Parameter("check.wait_timeout", value=0.2)])[0].successful  # in force at once
    node.gate.close()
    assert [r.successful for r in unsettled_set(node, [Parameter("payload.mass", value=7.0)])] == [True]
    reply = check(node)
    assert not reply.success and "\n" not in reply.message
    assert reply.message.startswith("UNPROVEN: the analysis of the new parameters is still running (waited ")
    assert reply.message.endswith(" s, check.wait_timeout): ask again later")
    node.gate.open()
    node.settle()
    assert check(node).message.startswith("OVER-LIMIT: 7.000 kg does not fit: ")


@pytest.mark.parametrize("value", [-1.0, 601.0, float("inf"), float("nan")])
def test_check_wait_timeout_is_refused_outside_its_range(gated_payload_node, value):
    [result] = gated_payload_node.set_parameters([Parameter("check.wait_timeout", value=value)])
    assert not result.successful and "check.wait_timeout out of range Min: 0.0, Max: 600.0" in result.reason
    assert gated_payload_node.node.get_parameter("check.wait_timeout").value == 30.0


def test_a_payload_change_reuses_the_limits_and_a_warn_use_change_the_analysis(gated_payload_node, monkeypatch):
    node = gated_payload_node
    derived = Gate(payload_analysis.derive_torque_limits)
    monkeypatch.setattr(payload_analysis, "derive_torque_limits", derived)
    limits = node.node.settings.analysis.limits
    assert [r.successful for r in node.set_parameters([Parameter("payload.mass", value=2.0)])] == [True]
    assert derived.calls == 0 and node.node.settings.analysis.limits is limits
    sweeps, workspace = node.gate.calls, node.node.settings.analysis.workspace
    assert node.node.set_parameters([Parameter("diagnostics.warn_use", value=50.0)])[0].successful
    assert node.node.rebuild.pending_since is None  # in force at once: nothing to analyse
    assert node.node.settings.warn_use == 50.0 and node.node.settings.analysis.workspace is workspace
    assert node.gate.calls == sweeps


def test_a_slow_first_analysis_does_not_hold_up_startup(monkeypatch):
    gate = Gate(payload_analysis.workspace_load)
    gate.close()
    monkeypatch.setattr(payload_analysis, "workspace_load", gate)
    monkeypatch.setattr(payload_module, "STARTUP_WAIT", 0.2)
    overrides = [Parameter("diagnostics.period", value=0.0)]
    with running(PayloadCheckNode, parameter_overrides=overrides) as harness:
        try:
            assert harness.node.settings is None
            client = harness.probe.create_client(Trigger, "/payload_check_node/check")
            assert client.wait_for_service(timeout_sec=TIMEOUT)
            future = client.call_async(Trigger.Request())  # held: the first analysis is under way
            assert harness.spin_until(lambda: harness.node.check_service.held == 1)
            assert not future.done()
        finally:
            gate.open()
        assert harness.spin_until(future.done)
        reply = future.result()
        assert reply.success and reply.message.startswith("OK: 0.000 kg fits, worst joint_"), reply.message


@pytest.mark.parametrize("make_node", [IdNode, PayloadCheckNode])
def test_undeclared_and_empty_names_are_refused_by_name(make_node):
    with running(make_node) as harness:
        for name in ("", "payload.mas"):
            [result] = harness.set_parameters([Parameter(name, value=1.0)])
            assert not result.successful and repr(name) in result.reason, result.reason
        result = harness.set_parameters_atomically([Parameter("payload.mass", value=1.0), Parameter("", value=1.0)])
        assert not result.successful and "['']" in result.reason
        client = harness.parameter_client()
        names = harness.call(lambda: client.list_parameters([], 0)).result.names
        assert "" not in names and "payload.mas" not in names
        assert harness.node.get_parameter("payload.mass").value == 0.0


def test_a_parameter_of_no_known_type_is_refused_and_the_node_goes_on():
    """rclpy itself raises on it inside the service callback, which would end the node."""
    with running(IdNode) as harness:
        bad = ParameterMsg(name="payload.mass", value=ParameterValue(type=99))
        good = Parameter("payload.mass", value=2.0).to_parameter_msg()
        client = harness.probe.create_client(SetParameters, "/id_node/set_parameters")
        atomic = harness.probe.create_client(SetParametersAtomically, "/id_node/set_parameters_atomically")
        assert client.wait_for_service(TIMEOUT) and atomic.wait_for_service(TIMEOUT)
        results = harness.call(lambda: client.call_async(SetParameters.Request(parameters=[bad, good]))).results
        assert [r.successful for r in results] == [False, True]
        assert results[0].reason == "'payload.mass': 99 is not a parameter type"
        result = harness.call(lambda: atomic.call_async(SetParametersAtomically.Request(parameters=[good, bad]))).result
        assert not result.successful
        harness.settle()
        assert harness.node.settings.model.payload.mass == 2.0
