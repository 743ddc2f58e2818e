"""Slow work off the executor: the newest job built in a worker thread, its result handed back.

``Rebuild.submit(job)`` builds ``build(job, previous)`` (compiling kernels, sweeping the
workspace: what would stall the messages) in a worker thread and gives the result to ``use``
on the executor thread through ``executor.create_task`` (run at once by every rclpy executor,
the EventsExecutor included). A newer job cancels the build under way (``core.payload.stop``),
so a burst of changes ends with the newest. ``submit`` lowers the interpreter's switch
interval (process-wide) so that the executor thread gets the lock quickly meanwhile.
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from irb140_dynamics.core.errors import one_line
from irb140_dynamics.core.payload.stop import Cancelled, stopping

SWITCH_INTERVAL = 2e-4  # s: how long the message thread may wait for the interpreter lock
EXECUTOR_WAIT = 0.01  # s: a build done before the node joins its executor waits for it in these steps


@dataclass(frozen=True)
class Failed:
    """A build that raised ``error``."""

    error: BaseException


class Rebuild:
    """``build(job, previous)`` off the executor, the newest only; ``use(result)`` on it, then
    ``settled()`` if given (also after a failure, which keeps what is in force). ``previous``:
    the last result built (None at first); ``pending_since``: time.monotonic() of the newest
    job not yet in force; ``failure``: why the newest build failed."""

    def __init__(self, node, build: Callable[[Any, Any], Any], use: Callable[[Any], None], settled=None):
        self._node = weakref.ref(node)  # a worker still building keeps no node alive (a failed start drops it)
        self._build, self._use, self._settled = build, use, settled
        self._lock = threading.Lock()
        self._generation = 0  # of the newest job
        self._cancel = threading.Event()  # of the newest job
        self._job: tuple[int, Any, threading.Event] | None = None  # the newest job, not yet started
        self._worker = False  # a worker thread is under way
        self._ready: tuple[int, Any] | None = None  # the newest result, not yet used
        self._built = threading.Event()  # set with _ready
        self.previous = None
        self.pending_since: float | None = None
        self.failure: str | None = None

    def submit(self, job: Any) -> None:
        """Build ``job`` in the worker thread (started when there is work, ending when there is none)."""
        if sys.getswitchinterval() > SWITCH_INTERVAL:
            sys.setswitchinterval(SWITCH_INTERVAL)
        with self._lock:
            self._job = (*self._next(pending=True), job)
            start, self._worker = not self._worker, True
        if start:
            threading.Thread(target=_run, args=(weakref.ref(self), self._build), daemon=True).start()

    def build_here(self, job: Any) -> None:
        """Build ``job`` on this thread (a quick one) and use it; builds under way are superseded."""
        with self._lock:
            self._next(pending=False)
        result = _built(self._build, job, self.previous)
        if not isinstance(result, Failed):
            self.previous = result
        self._deliver(result)

    def wait(self, timeout: float) -> bool:
        """Before spinning: wait up to ``timeout`` s for the newest result and use it here
        (a failure raised). True if it was used."""
        if not self._built.wait(timeout):
            return False
        ready = self._take(self._generation)
        if ready is None:
            return False
        if isinstance(ready[1], Failed):
            raise ready[1].error
        self._deliver(ready[1])
        return True

    def status(self) -> str | None:
        """None when the newest job is in force; else in words why not (yet)."""
        if self.failure is not None:
            return f"parameters accepted but not applied: {self.failure}"
        if self.pending_since is not None:
            return f"new parameters being applied (for {time.monotonic() - self.pending_since:.1f} s)"
        return None

    def _next(self, pending: bool) -> tuple[int, threading.Event]:
        """A new generation (under the lock): the build under way cancelled, results dropped."""
        self._cancel.set()
        self._cancel = threading.Event()
        self._generation += 1
        self._job = self._ready = None
        self._built.clear()
        if pending and self.pending_since is None:
            self.pending_since = time.monotonic()
        return self._generation, self._cancel

    def _take(self, generation: int) -> tuple[int, Any] | None:
        """The result ready, if it is of ``generation`` and that is the newest; else None."""
        with self._lock:
            ready = self._ready
            if ready is None or ready[0] != generation or generation != self._generation:
                return None
            self._ready = None
            self._built.clear()
        return ready

    def _deliver(self, result: Any) -> None:
        """Use a result (on the executor thread, or before spinning), or note its failure."""
        self.pending_since = None
        if isinstance(result, Failed):
            error = result.error
            self.failure = one_line(error) if isinstance(error, ValueError) else f"{type(error).__name__}: {error}"
            self._node().get_logger().error(f"new parameters not applied, the previous stay in force: {self.failure}")
        else:
            self.failure = None
            self._use(result)
        if self._settled is not None:
            self._settled()

    def next_job(self) -> tuple[int, threading.Event, Any, Any] | None:
        """The worker's: (generation, cancel, job, previous) of the newest job, or None (then
        the worker ends)."""
        with self._lock:
            if self._job is None:
                self._worker = False
                return None
            (generation, cancel, job), self._job = self._job, None
            return generation, cancel, job, self.previous

    def keep(self, generation: int, result: Any):
        """The worker's: keep a result of the newest job for the executor thread; the node
        to hand it over on, or None when a newer job came meanwhile."""
        with self._lock:
            if generation != self._generation:
                return None
            if not isinstance(result, Failed):
                self.previous = result
            self._ready = (generation, result)
            self._built.set()
        return self._node()

    def hand_over(self, generation: int) -> None:
        """On the executor thread: use the result unless a newer job came since (or it was used)."""
        ready = self._take(generation)
        if ready is not None:
            self._deliver(ready[1])


def _built(build: Callable[[Any, Any], Any], job: Any, previous: Any) -> Any:
    try:
        return build(job, previous)
    except Cancelled:
        raise
    except Exception as error:  # noqa: BLE001  (handed to the node, not raised in a thread)
        return Failed(error)


def _run(ref: weakref.ref, build: Callable[[Any, Any], Any]) -> None:
    """The worker thread: build the newest job of the Rebuild ``ref`` until there is none,
    handing each result over; it holds the Rebuild (and so its node) only between builds."""
    while (rebuild := ref()) is not None:
        taken = rebuild.next_job()
        del rebuild
        if taken is None:
            return
        generation, cancel, job, previous = taken
        try:
            with stopping(cancel):
                result = _built(build, job, previous)
        except Cancelled:
            continue
        rebuild = ref()
        node = None if rebuild is None else rebuild.keep(generation, result)
        del rebuild
        while node is not None and node.executor is None:  # a build done while the node is made waits for it
            if not node.context.ok() or cancel.wait(EXECUTOR_WAIT):
                node = None
        if node is None:
            continue
        with contextlib.suppress(Exception):  # the executor shut down meanwhile, or the node is gone: no one to tell
            node.executor.create_task(ref().hand_over, generation)
        del node
