"""A node's parameter services (the six of rcl_interfaces, as ``ros2 param`` calls them),
answered through the node's public parameter API, and safe against any request.

rclpy's own set services raise inside the callback on a parameter type they do not know (a
ParameterValue.type of 99, from a hand-made client), which ends the node's spin, and let
''  through to its internals. Here a set request refuses such a parameter by name, and an
unknown name naming the nearest known one; the rest is set as rclpy does, one by one
(SetParameters) or all or none (SetParametersAtomically), each change checked whole by the
node's own on-set callback. Any other failure is answered with an empty response and
warned about (throttled): the node goes on.
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
    """The six parameter services of ``node`` (``~/set_parameters``, ...)."""

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
                return answer(request, response) or response
            except Exception as error:  # noqa: BLE001  (no request may end the node)
                self._node.get_logger().warning(
                    f"{srv_type.__name__} request failed: {type(error).__name__}: {error}", throttle_duration_sec=2.0
                )
                return srv_type.Response()

        return callback

    def _declared(self, names) -> bool:
        return all(self._node.has_parameter(name) for name in names)

    def _describe(self, request, response) -> None:
        if self._declared(request.names):  # as rclpy: one name not declared, none answered
            response.descriptors = self._node.describe_parameters(list(request.names))

    def _get(self, request, response) -> None:
        if self._declared(request.names):
            with contextlib.suppress(ParameterUninitializedException):  # as rclpy: one without a value, none
                parameters = self._node.get_parameters(list(request.names))
                response.values = [p.get_parameter_value() for p in parameters]

    def _get_types(self, request, response) -> None:
        if self._declared(request.names):
            response.types = self._node.get_parameter_types(list(request.names))

    def _list(self, request, response) -> None:
        with contextlib.suppress(TypeError, ValueError):  # as rclpy: a bad request, an empty list
            response.result = self._node.list_parameters(list(request.prefixes), request.depth)

    def _set(self, request, response) -> None:
        """Each parameter set on its own, in order."""
        response.results = [self._set_all([message]) for message in request.parameters]

    def _set_atomically(self, request, response) -> None:
        response.result = self._set_all(request.parameters)

    def _set_all(self, messages) -> SetParametersResult:
        refusal = self._refusal(messages)
        return refusal or self._node.set_parameters_atomically(_parameters(messages))

    def _refusal(self, messages) -> SetParametersResult | None:
        """A parameter of no known type, or a name not declared, refused by name; else None."""
        for message in messages:
            if message.value.type not in PARAMETER_TYPES:
                return _refused(f"{message.name!r}: {message.value.type} is not a parameter type")
        return undeclared(self._node, [m.name for m in messages])


def undeclared(node: Node, names) -> SetParametersResult | None:
    """The refusal of the names not declared ('' included), naming the nearest known one; None when all are."""
    unknown = [name for name in names if not name or not node.has_parameter(name)]
    if not unknown:
        return None
    hint = nearest_hint(unknown[0], node.list_parameters([], 0).names) if unknown[0] else ""
    return _refused(
        f"undeclared parameter{'s' if len(unknown) > 1 else ''} {unknown}: not a parameter of this node{hint}"
    )


def _parameters(messages) -> list[Parameter]:
    return [Parameter.from_parameter_msg(message) for message in messages]


def _refused(reason: str) -> SetParametersResult:
    return SetParametersResult(successful=False, reason=reason)
