"""Slow work off the executor: the newest job built in a worker thread, its result handed back.

A node's executor thread serves its messages; building a new configuration there
(compiling kernels, sweeping the workspace) would stall them. ``Rebuild.submit(job)``
builds ``build(job, previous)`` in a worker thread and gives the result (or a ``Failed``)
to ``use`` on the node's executor thread, through ``executor.create_task``: rclpy's
executors, the EventsExecutor included, run a task made from another thread at once,
waking from their wait. Only the newest job counts: one submitted while another is built
cancels it (a build that checks ``core.payload.stop.out_of_time`` stops at its next
check and is dropped), so changes faster than builds end with the newest.

While a build runs, the executor thread must still get the interpreter lock quickly:
``submit`` lowers the interpreter's switch interval to SWITCH_INTERVAL (process-wide; it
only matters while two threads want to run Python, i.e. during builds).
"""

from __future__ import annotations

import sys
import threading
import time
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
    """``build(job, previous)`` off the executor, the newest only; ``use(result)`` on it.
    ``previous`` is the last result built (None at first)."""

    def __init__(self, node, build: Callable[[Any, Any], Any], use: Callable[[Any], None], settled=None):
        """``settled()``, if given, is called after each result is used or has failed."""
        self._node, self._build, self._use, self._settled = node, build, use, settled
        self._lock = threading.Lock()
        self._generation = 0  # of the newest job
        self._cancel = threading.Event()
        self._job: tuple[int, Any, threading.Event] | None = None  # the newest job not yet started
        self._worker = False  # a worker thread is under way
        self._ready: tuple[int, Any] | None = None  # the newest result, not yet used
        self._built = threading.Event()  # set with _ready
        self.previous = None
        self.pending_since: float | None = None  # time.monotonic() of the newest job not yet in force
        self.failure: str | None = None  # why the newest build failed (what was in force stays)

    def submit(self, job: Any) -> None:
        """Build ``job`` in the worker thread (started when there is work, ended when there is
        none); the build under way, if any, is cancelled, and jobs waiting collapse into this."""
        generation, cancel = self._next(pending=True)
        if sys.getswitchinterval() > SWITCH_INTERVAL:
            sys.setswitchinterval(SWITCH_INTERVAL)
        with self._lock:
            self._job = (generation, job, cancel)
            if self._worker:
                return
            self._worker = True
        threading.Thread(target=self._run, daemon=True).start()

    def build_here(self, job: Any) -> None:
        """Build ``job`` on this thread (a quick one) and use it; builds under way are superseded."""
        self._next(pending=False)
        self._deliver(self._built_from(job))

    def wait(self, timeout: float) -> bool:
        """Before spinning: wait up to ``timeout`` s for the newest result and use it here
        (its error raised). True if it was used."""
        if not self._built.wait(timeout):
            return False
        with self._lock:
            ready, self._ready = self._ready, None
            self._built.clear()
            if ready is None or ready[0] != self._generation:
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
        with self._lock:
            self._cancel.set()
            self._cancel = threading.Event()
            self._generation += 1
            self._job = None
            self._ready = None
            self._built.clear()
            if pending and self.pending_since is None:
                self.pending_since = time.monotonic()
            return self._generation, self._cancel

    def _deliver(self, result: Any) -> None:
        """Use a result (on the executor thread, or before spinning), or note its failure."""
        self.pending_since = None
        if isinstance(result, Failed):
            error = result.error
            self.failure = one_line(error) if isinstance(error, ValueError) else f"{type(error).__name__}: {error}"
            self._node.get_logger().error(f"new parameters not applied, the previous stay in force: {self.failure}")
        else:
            self.failure = None
            self._use(result)
        if self._settled is not None:
            self._settled()

    def _built_from(self, job: Any) -> Any:
        try:
            result = self.previous = self._build(job, self.previous)
        except Cancelled:
            raise
        except Exception as error:  # noqa: BLE001  (handed to the node, not raised in a thread)
            return Failed(error)
        return result

    def _run(self) -> None:
        """The worker thread: build the newest job until there is none."""
        while True:
            with self._lock:
                if self._job is None:
                    self._worker = False
                    return
                (generation, job, cancel), self._job = self._job, None
            try:
                with stopping(cancel):
                    result = self._built_from(job)
            except Cancelled:
                continue
            with self._lock:
                if generation != self._generation:
                    continue
                self._ready = (generation, result)
                self._built.set()
            executor = self._executor(cancel)
            if executor is not None:
                try:
                    executor.create_task(self._hand_over, generation)
                except Exception:  # noqa: BLE001  (the executor shut down meanwhile: nothing to hand over to)
                    continue

    def _executor(self, cancel: threading.Event):
        """The node's executor; a build done while the node is being made waits for it
        (None once superseded or shut down)."""
        node = self._node
        while node.executor is None:
            if not node.context.ok() or cancel.wait(EXECUTOR_WAIT):
                return None
        return node.executor

    def _hand_over(self, generation: int) -> None:
        """On the executor thread: use the result unless a newer job was submitted since
        (or it was used already)."""
        with self._lock:
            ready = self._ready
            if ready is None or ready[0] != generation or generation != self._generation:
                return
            self._ready = None
            self._built.clear()
        self._deliver(ready[1])
