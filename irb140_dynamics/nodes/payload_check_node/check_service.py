"""~/check (std_srvs/Trigger): answered for the parameters in force, waiting for their analysis.

Right after an accepted change the limits and the workspace analysis of the new parameters
run off the executor (see ros.runtime.rebuild). A request that comes meanwhile waits (its
callback is a coroutine: the executor goes on serving joint_states, the parameter services
and the timers) and is answered as soon as the analysis is in force or has failed, for the
parameters then in force; or, after ``check.wait_timeout`` seconds (a one-shot timer on the
steady clock), with ``UNPROVEN: the analysis of the new parameters is still running ...``.
At most MAX_HELD requests wait at once. Coroutine callbacks need one of rclpy's own
executors: the node spins on the SingleThreadedExecutor.
"""

from __future__ import annotations

from collections.abc import Callable

from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.clock import Clock, ClockType
from rclpy.task import Future
from std_srvs.srv import Trigger

from irb140_dynamics.core.errors import one_line

MAX_HELD = 1000  # requests waiting at once; more are answered at once, as after the wait
WAIT_PARAMETER = "check.wait_timeout"
STEADY = Clock(clock_type=ClockType.STEADY_TIME)


class CheckService:
    """~/check of a node: ``answer(request, response)`` answers now (the parameters in force
    analysed); ``pending()`` tells that an accepted change is still being analysed;
    ``settled()`` (the node calls it) lets the waiting requests go."""

    def __init__(self, node, answer: Callable, pending: Callable[[], bool], name: str = "~/check"):
        self._node, self._answer, self._pending = node, answer, pending
        self._waiting: list[Future] = []
        # reentrant: while a request waits, the node's other callbacks (in its default,
        # mutually exclusive group) run, and so do other requests
        node.create_service(Trigger, name, self._on_request, callback_group=ReentrantCallbackGroup())

    @property
    def held(self) -> int:
        """Requests waiting for an analysis."""
        return len(self._waiting)

    def settled(self) -> None:
        """The analysis in force (or failed): every waiting request is answered."""
        waiting, self._waiting = self._waiting, []
        for done in waiting:
            if not done.done():
                done.set_result(True)

    async def _on_request(self, request, response):
        try:
            if self._pending() and not await self._settled_in_time():
                return _still_running(response, self._wait())
            return self._answer(request, response)
        except Exception as error:  # noqa: BLE001  (the point: nothing escapes to the executor)
            self._node.tally.error("check", error)
            response.success = False
            response.message = f"UNPROVEN: not checked: internal error {type(error).__name__}: {one_line(error)}"
            return response

    def _wait(self) -> float:
        return float(self._node.get_parameter(WAIT_PARAMETER).value)

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


def _still_running(response, waited: float):
    response.success = False
    response.message = (
        f"UNPROVEN: the analysis of the new parameters is still running (waited {waited:.1f} s, "
        f"{WAIT_PARAMETER}): ask again later"
    )
    return response
