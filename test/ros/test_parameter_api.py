"""The parameters as a user meets them, through rclpy's public API: an integer for a double
taken at startup (``-p``, a params file, parameter_overrides) as at run time; an unknown
name refused naming the nearest known one; each parameter described (type, range,
read-only, description) by its descriptor; the parameter services answering as rclpy's."""

from __future__ import annotations

import re

import pytest
from rcl_interfaces.msg import ParameterType
from rclpy.node import Node
from rclpy.parameter import Parameter

from irb140_dynamics.core import RigidBody, irb140
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.sim_node.node import SimNode
from irb140_dynamics.ros.parameters.arm import declare_fixed
from irb140_dynamics.ros.parameters.spec import Spec

from ..support.ros_harness import running


def test_an_integer_for_a_double_at_startup_from_the_command_line_and_a_params_file(tmp_path):
    params = tmp_path / "arm.yaml"
    params.write_text("/**:\n  ros__parameters:\n    payload:\n      com: [0, 0, 1]\n")
    arguments = ["--ros-args", "-p", "payload.mass:=2", "--params-file", str(params)]
    with running(IdNode, cli_args=arguments) as harness:
        node = harness.node
        assert node.get_parameter("payload.mass").type_ == Parameter.Type.DOUBLE
        assert node.get_parameter("payload.com").type_ == Parameter.Type.DOUBLE_ARRAY
        assert node.settings.model == irb140(payload=RigidBody(2.0, (0.0, 0.0, 1.0)))


def test_an_integer_for_a_double_in_parameter_overrides():
    overrides = [Parameter("payload.mass", value=3), Parameter("joint_1.torque_limit", value=100)]
    with running(IdNode, parameter_overrides=overrides) as harness:
        assert harness.node.settings.model.payload.mass == 3.0
        assert harness.node.get_parameter("joint_1.torque_limit").value == 100.0


@pytest.mark.parametrize(
    "override, message",
    [
        (Parameter("payload.mass", value="heavy"), "payload.mass: expected a value of type double"),
        (Parameter("payload.mass", value=-1.0), "payload.mass: must be between 0 and 1e+06, got -1.0"),
        (Parameter("qos.depth", value=2.5), "qos.depth: expected a value of type integer"),
    ],
)
def test_a_bad_value_at_startup_is_one_line_naming_the_parameter(override, message):
    with (
        pytest.raises(ValueError, match="^" + re.escape(message) + "$"),
        running(IdNode, parameter_overrides=[override]),
    ):
        pass


def test_an_unknown_name_at_run_time_is_refused_naming_the_nearest_one():
    with running(IdNode) as harness:
        before = harness.node.settings
        [result] = harness.set_parameters([Parameter("payload.mas", value=2.0)])
        assert not result.successful and "did you mean payload.mass?" in result.reason, result.reason
        result = harness.set_parameters_atomically(
            [Parameter("payload.mass", value=2.0), Parameter("acceleration.mod", value="zero")]
        )
        assert not result.successful and "did you mean acceleration.mode?" in result.reason, result.reason
        assert harness.node.settings is before


def test_values_given_for_no_parameter_are_not_declared_and_use_sim_time_stays_rclpys():
    overrides = [Parameter("payload.mas", value=2.0), Parameter("use_sim_time", value=True)]
    with running(IdNode, parameter_overrides=overrides) as harness:
        node = harness.node
        assert not node.has_parameter("payload.mas")
        assert node.get_parameter("use_sim_time").value is True and node.get_clock().ros_time_is_active


def test_descriptors_state_type_range_read_only_and_description():
    with running(SimNode) as harness:
        client = harness.parameter_client()
        names = ["rate", "substeps", "payload.mass", "integrator", "initial_positions"]
        described = {d.name: d for d in harness.call(lambda: client.describe_parameters(names)).descriptors}
        assert [described[n].type for n in names] == [
            ParameterType.PARAMETER_DOUBLE,
            ParameterType.PARAMETER_INTEGER,
            ParameterType.PARAMETER_DOUBLE,
            ParameterType.PARAMETER_STRING,
            ParameterType.PARAMETER_DOUBLE_ARRAY,
        ]
        rate = described["rate"]
        assert rate.read_only and rate.description.endswith("[Hz]")
        assert (rate.floating_point_range[0].from_value, rate.floating_point_range[0].to_value) == (1.0, 100000.0)
        assert described["substeps"].integer_range[0].to_value == 1000
        assert not described["payload.mass"].read_only


def test_the_parameter_services_answer_as_rclpys():
    with running(IdNode) as harness:
        client = harness.parameter_client()
        names = harness.call(lambda: client.list_parameters([], 0)).result.names
        assert {"payload.mass", "joint_1.dh", "use_sim_time", "qos.depth"} <= set(names)
        values = harness.call(lambda: client.get_parameters(["payload.mass", "qos.depth"])).values
        assert (values[0].double_value, values[1].integer_value) == (0.0, 10)
        assert harness.call(lambda: client.get_parameters(["payload.mass", "payload.mas"])).values == []
        types = harness.call(lambda: client.get_parameter_types(["model.name"])).types
        assert list(types) == [ParameterType.PARAMETER_STRING]
        assert harness.call(lambda: client.describe_parameters(["nothing"])).descriptors == []


def test_a_node_made_without_node_options_is_a_defect_said_at_once():
    """Without them rclpy would keep the values given to itself: they would be lost silently."""

    class Forgetful(Node):
        def __init__(self, **kwargs):
            super().__init__("forgetful", **kwargs)
            declare_fixed(self, [Spec("period", 1.0, "a period", "s", minimum=0.0, maximum=10.0)])

    with pytest.raises(TypeError, match="without NODE_OPTIONS"), running(Forgetful):
        pass
