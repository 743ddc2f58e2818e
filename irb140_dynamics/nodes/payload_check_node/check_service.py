"""~/check (std_srvs/Trigger): answered for the parameters in force, waiting for their analysis.

Right after an accepted change the limits and the workspace analysis of the new parameters
run off the executor (see ros.runtime.builder). A request that comes meanwhile is held (a
``Later`` of ros.runtime.deferred_reply: the executor goes on serving joint_states, the
parameter services and the timers) and answered as soon as nothing is pending any more,
for the parameters then in force; or, after ``check.wait_timeout`` seconds, with
``UNPROVEN: the analysis of the new parameters is still running ...``. Held requests are
looked at every POLL_PERIOD by a timer on the steady clock (made once, cancelled while
nobody waits); at most MAX_HELD at once.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from std_srvs.srv import Trigger

from irb140_dynamics.core.errors import one_line
from irb140_dynamics.ros.runtime.builder import STEADY
from irb140_dynamics.ros.runtime.deferred_reply import DeferredService, Later
from irb140_dynamics.ros.runtime.guard import guarded

POLL_PERIOD = 0.01  # s: how soon a held request is answered once its analysis is in force
MAX_HELD = 1000  # requests held at once; more are answered at once, as after the wait
WAIT_PARAMETER = "check.wait_timeout"


def _internal_error(request, response, error):
    response.success = False
    response.message = f"UNPROVEN: not checked: internal error {type(error).__name__}: {one_line(error)}"
    return response


class CheckService:
    """~/check of a node: ``answer(request, response)`` answers now (the parameters in force
    analysed); ``pending()`` tells that an accepted change is still being analysed."""

    def __init__(self, node, answer: Callable, pending: Callable[[], bool], name: str = "~/check"):
        self._node, self._answer, self._pending = node, answer, pending
        self.tally = node.tally
        self._held: list[tuple[Later, float, float]] = []  # (reply, since, deadline) [time.monotonic()]
        self._timer = None
        DeferredService(node, Trigger, name, self._on_request)

    @property
    def held(self) -> int:
        """Requests waiting for an analysis."""
        return len(self._held)

    @guarded("check", fallback=_internal_error)
    def _on_request(self, request, response):
        if not self._pending():
            return self._answer(request, response)
        wait = float(self._node.get_parameter(WAIT_PARAMETER).value)
        now = time.monotonic()
        if wait <= 0.0 or len(self._held) >= MAX_HELD:
            return _still_running(response, 0.0)
        later = Later()
        self._held.append((later, now, now + wait))
        if self._timer is None:
            self._timer = self._node.create_timer(POLL_PERIOD, self._on_poll, clock=STEADY)
        elif self._timer.is_canceled():
            self._timer.reset()
        return later

    @guarded("check")
    def _on_poll(self) -> None:
        """Answer the held requests whose analysis is done, or whose wait has run out."""
        now, pending = time.monotonic(), self._pending()
        keep = []
        for later, since, deadline in self._held:
            if not pending:
                later.answer(self._answered(Trigger.Request(), Trigger.Response()))
            elif now >= deadline:
                later.answer(_still_running(Trigger.Response(), now - since))
            else:
                keep.append((later, since, deadline))
        self._held = keep
        if not keep:
            self._timer.cancel()

    def _answered(self, request, response):
        """The answer now, an error of ours answered as one (and counted)."""
        try:
            return self._answer(request, response)
        except Exception as error:  # noqa: BLE001  (a held request is answered whatever happens)
            self.tally.error("check", error)
            return _internal_error(request, response, error)


def _still_running(response, waited: float):
    response.success = False
    response.message = (
        f"UNPROVEN: the analysis of the new parameters is still running (waited {waited:.1f} s, "
        f"{WAIT_PARAMETER}): ask again later"
    )
    return response
