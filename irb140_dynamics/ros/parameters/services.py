"""A node's six parameter services (as ``ros2 param`` calls them), answered through the node's
public parameter API and safe against any request.

rclpy's own set services raise inside the callback on a parameter type they do not know (a
ParameterValue.type of 99, from a hand-made client), which ends the node's spin, and let
'' through to its internals. Here such a parameter, or a name not declared, is refused by
name (with the nearest known one); the rest is set as rclpy sets it, each change checked
whole by the node's on-set callback. Any other failure is an empty response and a warning.
"""

from __future__ import annotations

import contextlib

from rcl_interfaces.msg import SetParametersResult
from rcl_interfaces.srv import (
    DescribeParameters,
    GetParameters,
    GetParameterTypes,
    ListParameters,
    SetParameters,
    SetParametersAtomically,
)
from rclpy.exceptions import ParameterUninitializedException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import qos_profile_parameters

from irb140_dynamics.core.io.parameter_names import nearest_hint

PARAMETER_TYPES = {kind.value for kind in Parameter.Type}


class ParameterServices:
    """The parameter services of ``node`` (``~/set_parameters``, ...)."""

    def __init__(self, node: Node):
        self._node = node
        for srv_type, name, answer in (
            (DescribeParameters, "describe_parameters", self._describe),
            (GetParameters, "get_parameters", self._get),
            (GetParameterTypes, "get_parameter_types", self._get_types),
            (ListParameters, "list_parameters", self._list),
            (SetParameters, "set_parameters", self._set),
            (SetParametersAtomically, "set_parameters_atomically", self._set_atomically),
        ):
            node.create_service(
                srv_type,
                f"{node.get_name()}/{name}",
                self._answered(srv_type, answer),
                qos_profile=qos_profile_parameters,
            )

    def _answered(self, srv_type, answer):
        def callback(request, response):
            try:
                answer(request, response)
                return response
            except Exception as error:  # noqa: BLE001  (no request may end the node)
                why = f"{srv_type.__name__} request failed: {type(error).__name__}: {error}"
                self._node.get_logger().warning(why, throttle_duration_sec=2.0)
                return srv_type.Response()

        return callback

    def _declared(self, names) -> bool:  # as rclpy: one name not declared, none answered
        return all(self._node.has_parameter(name) for name in names)

    def _describe(self, request, response) -> None:
        if self._declared(request.names):
            response.descriptors = self._node.describe_parameters(list(request.names))

    def _get(self, request, response) -> None:
        if self._declared(request.names):
            with contextlib.suppress(ParameterUninitializedException):  # as rclpy: one without a value, none
                response.values = [p.get_parameter_value() for p in self._node.get_parameters(list(request.names))]

    def _get_types(self, request, response) -> None:
        if self._declared(request.names):
            response.types = self._node.get_parameter_types(list(request.names))

    def _list(self, request, response) -> None:
        with contextlib.suppress(TypeError, ValueError):  # as rclpy: a bad request, an empty list
            response.result = self._node.list_parameters(list(request.prefixes), request.depth)

    def _set(self, request, response) -> None:  # each parameter on its own, in order
        response.results = [self._set_all([message]) for message in request.parameters]

    def _set_atomically(self, request, response) -> None:
        response.result = self._set_all(request.parameters)

    def _set_all(self, messages) -> SetParametersResult:
        for message in messages:
            if message.value.type not in PARAMETER_TYPES:
                return SetParametersResult(
                    successful=False, reason=f"{message.name!r}: {message.value.type} is not a parameter type"
                )
        refused = undeclared(self._node, [message.name for message in messages])
        return refused or self._node.set_parameters_atomically([Parameter.from_parameter_msg(m) for m in messages])


def undeclared(node: Node, names) -> SetParametersResult | None:
    """The refusal of the names not declared ('' included), naming the nearest known one; None when all are."""
    unknown = [name for name in names if not name or not node.has_parameter(name)]
    if not unknown:
        return None
    hint = nearest_hint(unknown[0], node.list_parameters([], 0).names) if unknown[0] else ""
    plural = "s" if len(unknown) > 1 else ""
    return SetParametersResult(
        successful=False, reason=f"undeclared parameter{plural} {unknown}: not a parameter of this node{hint}"
    )
