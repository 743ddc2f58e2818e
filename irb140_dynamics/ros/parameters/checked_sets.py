"""Parameter changes from the parameter services, checked off the executor.

rclpy checks a change in the node's on-set callback, on the executor thread, and answers at
once. Checking a whole configuration (a model of many joints) there would hold up every
message meanwhile. ``CheckedSets`` runs the check in a worker thread first (one at a time,
in the order requested) from the values the change would give; back on the executor thread
the change is set through ``set_parameters_atomically``, whose on-set callback takes the
result checked for exactly those values (see ``LiveParameters``) instead of checking
again, and the reply is sent. If anything changed in between (another change, a new URDF)
the on-set callback checks again, there. Results come back through a timer
polling while checks are under way (the EventsExecutor takes no guard conditions).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter

from irb140_dynamics.ros.parameters.services import Answer
from irb140_dynamics.ros.runtime.builder import POLL_PERIOD, STEADY


class CheckedSets:
    """``submit(parameters, answer)``: check in a worker, then set and ``answer(result)``."""

    def __init__(self, node: Node, snapshot: Callable[[list[Parameter]], Any], check: Callable[[Any], Any], checked):
        """``snapshot(changes)``: what the check of the changes starts from (the values they
        give); ``check(snapshot)``: the draft, or an error; ``checked(snapshot, future)``:
        hands the result to the on-set callback (``checked(None)`` after the set)."""
        self._node, self._snapshot, self._check, self._checked = node, snapshot, check, checked
        self._pool: ThreadPoolExecutor | None = None  # while checks are under way
        self._pending: deque[tuple[Future, list[Parameter], Any, Answer]] = deque()
        self._poll = None

    def submit(self, parameters: list[Parameter], answer: Answer) -> None:
        """On the executor thread: check ``parameters`` in the worker, then set them."""
        snapshot = self._snapshot(parameters)
        if self._pool is None:
            self._pool = ThreadPoolExecutor(1, thread_name_prefix=f"{self._node.get_name()} checks")
        self._pending.append((self._pool.submit(self._check, snapshot), parameters, snapshot, answer))
        if self._poll is None:
            self._poll = self._node.create_timer(POLL_PERIOD, self._deliver, clock=STEADY)
        elif self._poll.is_canceled():
            self._poll.reset()

    def _deliver(self) -> None:
        """On the executor thread: set the changes whose checks are done, in order."""
        while self._pending and self._pending[0][0].done():
            future, parameters, snapshot, answer = self._pending.popleft()
            self._checked(snapshot, future)
            try:
                result = self._node.set_parameters_atomically(parameters)
            except Exception as error:  # noqa: BLE001  (no request may end the node)
                result = SetParametersResult(successful=False, reason=f"{type(error).__name__}: {error}")
            finally:
                self._checked(None)
            try:
                answer(result)
            except Exception as error:  # noqa: BLE001  (a client gone meanwhile must not end the node)
                self._node.get_logger().warning(
                    f"parameter change set, reply not sent: {type(error).__name__}: {error}"
                )
        if not self._pending:
            self._poll.cancel()
            self._pool.shutdown(wait=False)  # no thread lingers between changes
            self._pool = None
