"""payload_check_node as its own process (the EventsExecutor main() uses): ~/check held while
the analysis of new parameters runs, then answered for them; an analysis out of time
answers UNPROVEN."""

import pytest
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from std_srvs.srv import Trigger

from ..support.chains import chain_urdf
from ..support.node_process import TIMEOUT

ANALYSIS = 120.0  # s: the longest an analysis here may take on a loaded 2-core machine


def call_check(probe, client):
    future = client.call_async(Trigger.Request())
    probe.spin_until(future.done, timeout=ANALYSIS)
    return future.result()


@pytest.mark.slow
def test_check_waits_for_the_analysis_in_the_node_process(probe, process, tmp_path):
    """A 30-joint chain, its analysis cut at 3 s: the node is up after 2 s, ~/check waits
    for the rest; a payload change then is answered for the new payload."""
    urdf = tmp_path / "chain_30.urdf"
    urdf.write_text(chain_urdf(30))
    process(
        "irb140_dynamics.nodes.payload_check_node.node",
        *("-p", "model.source:=robot_description", "-p", f"model.urdf_file:={urdf}"),
        *("-p", "check.analysis_timeout:=3.0", "-p", "payload.mass:=3.0", "-p", "diagnostics.period:=0.0"),
    )
    client = probe.create_client(Trigger, "/payload_check_node/check")
    assert client.wait_for_service(timeout_sec=TIMEOUT)
    reply = call_check(probe, client)
    first = reply.message.splitlines()[0]
    assert not reply.success and first.startswith("UNPROVEN: 3.000 kg not proven to fit: "), first
    assert "the analysis ran out of time" in first

    parameters = AsyncParameterClient(probe, "payload_check_node")
    assert parameters.wait_for_services(timeout_sec=TIMEOUT)
    future = parameters.set_parameters([Parameter("payload.mass", value=4.0)])
    probe.spin_until(future.done)
    assert future.result().results[0].successful
    reply = call_check(probe, client)  # right after the change: its analysis, 3 s, is under way
    lines = reply.message.splitlines()
    assert lines[0].startswith("UNPROVEN: 4.000 kg not proven to fit: ") and "ran out of time" in lines[0]
    assert lines[1] == "payload 4.000 kg at (0.000, 0.000, 0.000) m"
