"""payload_check_node's ~/check on models beyond the proofs' budget and after a model change: a
long chain answers UNPROVEN with its best bound,
never OVER-LIMIT; an analysis out of time answers UNPROVEN and says so; a model change
cancels the analysis of the model before at its next check, and ~/check answers for the
new model."""

import threading

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.parameter import Parameter
from std_msgs.msg import String
from std_srvs.srv import Trigger

from irb140_dynamics.core import RigidBody, irb140
from irb140_dynamics.core.payload import check_payload, stop
from irb140_dynamics.core.urdf import export_urdf, load_urdf
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode
from irb140_dynamics.ros.parameters.arm import DESCRIPTION_QOS

from ..support.chains import chain_urdf
from ..support.ros_harness import TIMEOUT, running

ANALYSIS = 120.0  # s: the longest an analysis here may take on a loaded 2-core machine
pytestmark = pytest.mark.slow  # each some 3 s on an idle machine, over 5 s on a loaded one


def from_urdf(**values) -> list[Parameter]:
    values = {"model.source": "robot_description", "diagnostics.period": 0.0, **values}
    return [Parameter(name.replace("__", "."), value=value) for name, value in values.items()]


def check(harness):
    """~/check's reply, however long the analysis it waits for takes (up to ANALYSIS)."""
    client = harness.probe.create_client(Trigger, "/payload_check_node/check")
    assert client.wait_for_service(timeout_sec=TIMEOUT)
    future = client.call_async(Trigger.Request())
    assert harness.spin_until(future.done, ANALYSIS), "no answer"
    return future.result()


def test_a_long_chain_whose_payload_fits_is_unproven_not_over_limit():
    """The reported case: a 9-joint URDF arm was called OVER-LIMIT at 703,992 % of a limit,
    its bound taken for a torque. 12 joints here: the interval bounds' budget is spent."""
    text = chain_urdf(12)
    with running(PayloadCheckNode, parameter_overrides=from_urdf(robot_description=text, payload__mass=3.0)) as harness:
        diagnostics = harness.listen(DiagnosticArray, "/diagnostics")
        reply = check(harness)
        assert harness.spin_until(lambda: diagnostics)  # published with each check
    lines = reply.message.splitlines()
    statuses = {status.name.split(": ")[-1]: status for status in diagnostics[-1].status}
    assert statuses["payload"].message == lines[0]
    assert statuses["joint_2"].level == DiagnosticStatus.WARN  # not ERROR: nothing is proven over
    assert statuses["joint_2"].message.startswith("unproven: ")
    assert not reply.success and lines[0].startswith("UNPROVEN: 3.000 kg not proven to fit: "), lines[0]
    assert lines[1] == "payload 3.000 kg at (0.000, 0.000, 0.000) m"
    assert len([line for line in lines if line.startswith("joint_")]) == 12
    model = load_urdf(text).model
    assert lines[0] == check_payload(model, RigidBody(3.0)).headline()  # the core's verdict, same numbers


def test_an_analysis_out_of_time_answers_unproven():
    """A 30-joint chain (its search alone takes tens of seconds) within 0.5 s."""
    overrides = from_urdf(robot_description=chain_urdf(30), check__analysis_timeout=0.5, payload__mass=3.0)
    with running(PayloadCheckNode, parameter_overrides=overrides) as harness:
        reply = check(harness)
        assert harness.node.settings.analysis.workspace.out_of_time
    first = reply.message.splitlines()[0]
    assert not reply.success and first.startswith("UNPROVEN: 3.000 kg not proven to fit: ")
    assert "the analysis ran out of time" in first


def test_a_model_change_cancels_the_analysis_of_the_model_before(monkeypatch):
    """The reported case: after a model change ~/check said "pending" for over 120 s while
    the analysis of a 30-joint chain ran on. Its analysis (no time limit here) must stop
    at its first check after the new model came, and ~/check answer for the new model."""
    started, survived, raised = threading.Event(), [], []
    real = stop.Stop.out_of_time

    def counting(self):
        cancelled = self.cancel is not None and self.cancel.is_set()  # (a build's own stop)
        started.set()
        try:
            result = real(self)  # raises once cancelled
        except stop.Cancelled:
            raised.extend([self] if self.cancel is not None else [])
            raise
        if cancelled:
            survived.append(self)  # a check after the cancel that did not stop it
        return result

    monkeypatch.setattr(stop.Stop, "out_of_time", counting)
    with running(PayloadCheckNode, parameter_overrides=from_urdf(check__analysis_timeout=3600.0)) as harness:
        description = harness.probe.create_publisher(String, "robot_description", DESCRIPTION_QOS)
        description.publish(String(data=chain_urdf(30)))
        assert harness.spin_until(started.is_set, ANALYSIS), "the 30-joint analysis did not start"
        description.publish(String(data=export_urdf(irb140())))
        reply = check(harness)  # waits for whatever is pending: the newest model's analysis
        assert harness.node.settings.model.n == 6
    assert reply.success and reply.message.startswith("OK: 0.000 kg fits, worst joint_"), reply.message
    assert len([line for line in reply.message.splitlines() if line.startswith("joint_")]) == 6
    assert len(raised) == 1 and survived == []  # the 30-joint analysis, cancelled at its first check after
