"""No exception of ours leaves a ROS callback: what fails is dropped, counted and warned about.

``Tally`` keeps a node's message counts by ``<topic>.<what>`` (``joint_states.received``,
``joint_states.dropped_not_finite``, ...: fixed sets of keys, so the counts stay bounded)
and warns at most once every ``WARN_PERIOD`` seconds per topic. ``guarded(topic)`` wraps a
callback method: an exception escaping it is counted as ``<topic>.errors``, warned about,
and the node goes on (a service then answers ``fallback(request, response, error)``).
"""

from __future__ import annotations

import functools
import time
from collections import Counter
from collections.abc import Callable

WARN_PERIOD = 2.0  # s between two warnings about the same topic


class Tally:
    def __init__(self, logger, warn_period: float = WARN_PERIOD):
        self.counts: Counter[str] = Counter()
        self._logger = logger
        self._warn_period = warn_period
        self._next_warning: dict[str, float] = {}  # topic -> time.monotonic() it may warn again

    def add(self, topic: str, what: str) -> None:
        self.counts[f"{topic}.{what}"] += 1

    def drop(self, topic: str, error) -> None:
        """A message of ``topic`` dropped for ``error``, a BadMessage (its ``kind`` a short tag)."""
        self.counts[f"{topic}.dropped_{error.kind}"] += 1
        self.counts[f"{topic}.dropped"] += 1
        self.warn(topic, f"dropped a {topic} message ({error})")

    def error(self, topic: str, error: BaseException) -> None:
        """An exception of ours in a callback of ``topic`` (a defect: it is logged as such)."""
        self.counts[f"{topic}.errors"] += 1
        self.warn(topic, f"error in the {topic} callback, dropped: {type(error).__name__}: {error}")

    def warn(self, topic: str, text: str) -> None:
        now = time.monotonic()
        if now < self._next_warning.get(topic, 0.0):
            return
        self._next_warning[topic] = now + self._warn_period
        self._logger.warning(text)

    def total(self, what: str) -> int:
        """The sum over topics of ``<topic>.<what>`` (e.g. dropped, errors)."""
        suffix = f".{what}"
        return sum(count for key, count in self.counts.items() if key.endswith(suffix))


def guarded(topic: str, fallback: Callable | None = None):
    """Decorate a callback method of a node that has a ``tally``: no exception leaves it."""

    def decorate(method):
        @functools.wraps(method)
        def callback(node, *args):
            try:
                return method(node, *args)
            except Exception as error:  # noqa: BLE001  (the point: nothing escapes to the executor)
                node.tally.error(topic, error)
                return None if fallback is None else fallback(*args, error)

        return callback

    return decorate
