"""What a user sees of the nodes besides their topics: an integer
for a double at run time (`ros2 param set /id_node joint_1.torque_limit 100`), and the
robot's name as the hardware_id of /diagnostics (model.name, or the URDF's <robot name>)."""

from __future__ import annotations

import uuid

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.parameter import Parameter

from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode
from irb140_dynamics.nodes.sim_node.node import SimNode

from ..support.paths import URDF_DATA
from ..support.ros_harness import running

NODES = {"id_node": IdNode, "payload_check_node": PayloadCheckNode, "sim_node": SimNode}


def test_an_integer_for_a_double_at_run_time_is_taken_as_that_double():
    with running(IdNode) as harness:
        result = harness.set_parameters([Parameter("joint_1.torque_limit", Parameter.Type.INTEGER, 100)])[0]
        assert result.successful, result.reason
        value = harness.node.get_parameter("joint_1.torque_limit").value
        assert isinstance(value, float) and value == 100.0
        assert harness.node.settings.model.joints[0].torque_limit == 100.0
        result = harness.set_parameters([Parameter("payload.com", Parameter.Type.INTEGER_ARRAY, [0, 0, 1])])[0]
        assert result.successful, result.reason
        assert list(harness.node.settings.model.payload.com) == [0.0, 0.0, 1.0]


def hardware_ids(harness) -> set[str]:
    """The hardware_ids of the node's own statuses (other nodes of the domain publish there too)."""
    inbox = harness.listen(DiagnosticArray, "/diagnostics")
    own = f"{harness.node.get_name()}:"

    def statuses():
        return [status for msg in inbox for status in msg.status if status.name.startswith(own)]

    assert harness.spin_until(lambda: statuses())
    return {status.hardware_id for status in statuses()}


def renamed(name: str) -> list[str]:
    """cli_args giving the node a name of this test's own."""
    return ["--ros-args", "-r", f"__node:={name}_{uuid.uuid4().hex[:8]}"]


@pytest.mark.parametrize("name", sorted(NODES))
def test_diagnostics_name_the_robot_of_the_model(name):
    with running(NODES[name], cli_args=renamed(name)) as harness:
        assert hardware_ids(harness) == {"irb140"}
    overrides = [Parameter("model.name", value="cell_3_arm")]
    with running(NODES[name], parameter_overrides=overrides, cli_args=renamed(name)) as harness:
        assert hardware_ids(harness) == {"cell_3_arm"}


@pytest.mark.parametrize("name", ["id_node", "sim_node"])
def test_diagnostics_of_a_urdf_model_name_its_robot(name):
    overrides = [
        Parameter("model.source", value="robot_description"),
        Parameter("model.urdf_file", value=str(URDF_DATA / "ur5.urdf")),
        Parameter("model.tip_link", value="tool0"),
    ]
    with running(NODES[name], parameter_overrides=overrides, cli_args=renamed(name)) as harness:
        assert hardware_ids(harness) == {"ur5"}
