"""rclpy's parameter services of a node, made safe against malformed requests.

rclpy turns each requested parameter into a Parameter before anything checks it: a
parameter type it does not know (a ParameterValue.type of 99, from a hand-made client)
raises ValueError inside the service callback, which ends the node's spin. Here the set
services refuse such a parameter by name and handle the others as rclpy does, one by one
(SetParameters) or not at all (SetParametersAtomically); any other failure of a parameter
service is answered with an empty response and logged, the node goes on.
"""

from __future__ import annotations

import functools

from rcl_interfaces.msg import SetParametersResult
from rcl_interfaces.srv import SetParameters, SetParametersAtomically
from rclpy.node import Node
from rclpy.parameter import Parameter

PARAMETER_TYPES = {kind.value for kind in Parameter.Type}


def guard_parameter_services(node: Node) -> None:
    """Wrap the callbacks of the node's parameter services (rclpy's ParameterService)."""
    for service in node.services:
        if service.srv_type is SetParameters:
            service.callback = _one_by_one(service.callback)
        elif service.srv_type is SetParametersAtomically:
            service.callback = _all_or_none(service.callback)
        if service.srv_type.__module__.startswith("rcl_interfaces"):
            service.callback = _answered(node, service.callback, service.srv_type)


def _unknown_type(parameter) -> SetParametersResult | None:
    if parameter.value.type in PARAMETER_TYPES:
        return None
    return SetParametersResult(
        successful=False, reason=f"{parameter.name!r}: {parameter.value.type} is not a parameter type"
    )


def _one_by_one(callback):
    @functools.wraps(callback)
    def set_parameters(request, response):
        for parameter in request.parameters:
            refusal = _unknown_type(parameter)
            if refusal is None:
                one = callback(SetParameters.Request(parameters=[parameter]), SetParameters.Response())
                response.results.extend(one.results)
            else:
                response.results.append(refusal)
        return response

    return set_parameters


def _all_or_none(callback):
    @functools.wraps(callback)
    def set_parameters_atomically(request, response):
        for parameter in request.parameters:
            refusal = _unknown_type(parameter)
            if refusal is not None:
                response.result = refusal
                return response
        return callback(request, response)

    return set_parameters_atomically


def _answered(node: Node, callback, srv_type):
    @functools.wraps(callback)
    def answered(request, response):
        try:
            return callback(request, response)
        except Exception as error:  # noqa: BLE001  (rclpy's, but it would end our node)
            node.get_logger().warning(
                f"{srv_type.__name__} request failed: {type(error).__name__}: {error}", throttle_duration_sec=2.0
            )
            return srv_type.Response()

    return answered
