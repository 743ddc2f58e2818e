"""~/check (std_srvs/Trigger), answered for the parameters in force once they are analysed.

An accepted change is analysed off the executor (ros.runtime.rebuild). A request that comes
meanwhile waits, as a coroutine: the node's SingleThreadedExecutor goes on serving its other
callbacks. It is answered once the analysis is in force or has failed, or after
check.wait_timeout seconds (a one-shot timer on the steady clock) UNPROVEN, still running.
At most MAX_HELD requests wait at once; more are answered as after the wait.
"""

from __future__ import annotations

from collections.abc import Callable

from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.clock import Clock, ClockType
from rclpy.task import Future
from std_srvs.srv import Trigger

from irb140_dynamics.core.errors import one_line

MAX_HELD = 1000
STEADY = Clock(clock_type=ClockType.STEADY_TIME)


def reply(response, success: bool, message: str):
    """A std_srvs/Trigger response, filled."""
    response.success, response.message = success, message
    return response


class CheckService:
    """~/check of ``node``: ``answer(request, response)`` answers for the parameters in force;
    while ``pending()``, a request waits for ``settled()``."""

    def __init__(self, node, answer: Callable, pending: Callable[[], bool]):
        self._node, self._answer, self._pending = node, answer, pending
        self._waiting: list[Future] = []
        # reentrant: while a request waits, the node's other callbacks and requests run
        node.create_service(Trigger, "~/check", self._on_request, callback_group=ReentrantCallbackGroup())

    @property
    def held(self) -> int:
        """Requests waiting for an analysis."""
        return len(self._waiting)

    def settled(self) -> None:
        """The analysis in force, or failed: every waiting request is answered."""
        waiting, self._waiting = self._waiting, []
        for done in waiting:
            if not done.done():
                done.set_result(True)

    async def _on_request(self, request, response):
        try:
            if self._pending() and not await self._settled_in_time():
                waited = f"waited {self._wait():.1f} s, check.wait_timeout"
                return reply(
                    response,
                    False,
                    f"UNPROVEN: the analysis of the new parameters is still running ({waited}): ask again later",
                )
            return self._answer(request, response)
        except Exception as error:  # noqa: BLE001  (the point: nothing escapes to the executor)
            self._node.tally.error("check", error)
            return reply(
                response, False, f"UNPROVEN: not checked: internal error {type(error).__name__}: {one_line(error)}"
            )

    def _wait(self) -> float:
        return float(self._node.get_parameter("check.wait_timeout").value)

    async def _settled_in_time(self) -> bool:
        """Wait for the analysis, at most check.wait_timeout: True if it settled."""
        wait = self._wait()
        if wait <= 0.0 or len(self._waiting) >= MAX_HELD:
            return False
        done = Future()
        self._waiting.append(done)
        timer = self._node.create_timer(wait, lambda: done.done() or done.set_result(False), clock=STEADY)
        try:
            return await done
        finally:
            self._node.destroy_timer(timer)
            if done in self._waiting:
                self._waiting.remove(done)
