"""A service that may answer a request later, without holding up the executor meanwhile.

rclpy calls a service's callback on the executor thread and sends what it returns at once:
a callback that waited there (for work off the executor, say) would stall every other
callback of the node, and rclpy's EventsExecutor takes no coroutine callbacks to await in.
``DeferredService`` lets the callback return ``Later()`` instead of a response: the
executor hands it, with the request's header, to the service's ``send_response``, which
here keeps the header instead of sending; ``Later.answer(response)`` sends the reply when
it is ready (on the executor thread: from a timer or another callback). Both rclpy
executors (the Python ones and the EventsExecutor) send a reply through the service
object's ``send_response``, which is what this takes over.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


class Later:
    """A reply to be sent later: ``answer(response)`` sends it (once)."""

    def __init__(self) -> None:
        self._send: Callable[[Any, Any], None] | None = None
        self._header = None
        self._response = None
        self.answered = False

    def answer(self, response) -> None:
        """Send ``response`` to the request (at once if its header has come, else when it does)."""
        if self.answered:
            return
        self.answered = True
        if self._header is not None:
            self._send(response, self._header)
        else:
            self._response = response

    def _hold(self, send: Callable[[Any, Any], None], header) -> None:
        self._send, self._header = send, header
        if self._response is not None:
            response, self._response = self._response, None
            send(response, header)


class DeferredService:
    """A service whose ``callback(request, response)`` returns a response, or a Later."""

    def __init__(self, node, srv_type, name: str, callback: Callable[[Any, Any], Any], **kwargs):
        self.service = node.create_service(srv_type, name, callback, **kwargs)
        self._send = self.service.send_response
        self.service.send_response = self._send_or_hold  # the executors call it by attribute

    def _send_or_hold(self, response, header) -> None:
        if isinstance(response, Later):
            response._hold(self._send, header)
        else:
            self._send(response, header)
