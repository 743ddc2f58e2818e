"""Slow work off the executor: a worker thread builds, the executor thread swaps the result in.

A node's executor thread serves its messages; building a new configuration (compiling
kernels, sweeping the workspace) there would stall them. ``Builder.submit`` hands the
work to a worker thread, started when there is work and ended when there is none (a
thread that lingered for the next job kept the last result, and what it holds, alive past
its node); the result comes back to the executor thread through a timer polling every
POLL_PERIOD while a build is under way (the EventsExecutor takes no guard conditions; the
timer is made once and cancelled in between: rcl leaks ~80 B per timer made), whose
callback hands it to ``deliver``. The
timer runs on the steady clock, so that a node on simulated time (use_sim_time) takes its
parameter changes while the simulation stands still too. Only the newest job waiting is
kept: jobs submitted while one is being built collapse into the latest, and every job
finished is delivered (in order). A job submitted while another is being built cancels
that one (so does the shutdown of the node's context): a build that checks
``core.payload.stop.out_of_time`` (the payload analysis does) stops at its next check and
is not delivered, so the newest follows as soon as if the old had never started; a build
that does not check (compiling kernels) runs to its end, and the newest follows it.

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

from rclpy.clock import Clock, ClockType

from irb140_dynamics.core.payload.stop import Cancelled, stopping

SWITCH_INTERVAL = 2e-4  # s: how long the message thread may wait for the interpreter lock
POLL_PERIOD = 0.002  # s: how soon a finished build is swapped in
STEADY = Clock(clock_type=ClockType.STEADY_TIME)


@dataclass(frozen=True)
class Failed:
    """A build that raised ``error``."""

    error: BaseException


class _Work:
    """What the worker thread shares with the executor thread. It holds no node: a thread
    still building must not keep a node alive (a failed start destroys it at once)."""

    def __init__(self, build: Callable[[Any, Any], Any]):
        self.build = build
        self.lock = threading.Lock()
        self.job: tuple[int, Any] | None = None  # the newest job not yet started
        self.busy = False  # a job is waiting or being built
        self.thread = False  # a worker thread is under way
        self.finished: tuple[int, Any] | None = None  # the newest result not yet delivered
        self.done = threading.Event()  # set whenever a result is waiting to be delivered
        self.previous = None  # the last result built
        self.cancel = threading.Event()  # set to cancel the build under way
        self.cancelled = 0  # builds cancelled (superseded, or the context shut down)

    def run(self) -> None:
        """The worker thread: build jobs until there are none."""
        while True:
            with self.lock:
                if self.job is None:  # (a job dropped by stop() leaves nothing to wait for)
                    self.thread = self.busy = False
                    return
                (generation, job), self.job = self.job, None
                cancel = self.cancel = threading.Event()
            try:
                with stopping(cancel):
                    result = self.previous = self.build(job, self.previous)
            except Cancelled:
                with self.lock:
                    self.cancelled += 1
                    self.busy = self.job is not None
                continue
            except Exception as error:  # noqa: BLE001  (reported to the node, not raised in a thread)
                result = Failed(error)
            with self.lock:
                self.finished = (generation, result)
                self.busy = self.job is not None
                self.done.set()

    def submit(self, generation: int, job: Any, name: str) -> None:
        with self.lock:
            self.job = (generation, job)
            self.busy = True
            self.cancel.set()  # the build under way, if any, is superseded
            if not self.thread:
                self.thread = True
                threading.Thread(target=self.run, name=name, daemon=True).start()

    def stop(self) -> None:
        """Drop the job waiting and cancel the one under way (superseded by a build done
        elsewhere, or the context shuts down)."""
        with self.lock:
            self.job = None
            self.cancel.set()


class Builder:
    """Runs ``build(job, previous)`` in a worker thread; ``deliver(generation, result)`` on
    the node's executor thread (``previous``: the last result built, None at first; a
    result is a Failed when the build raised)."""

    def __init__(self, node, build: Callable[[Any, Any], Any], deliver: Callable[[int, Any], None], name: str):
        self._node, self._deliver, self._name = node, deliver, name
        self._work = _Work(build)
        self._poll = None  # the timer, while a build is under way
        node.context.on_shutdown(self._work.stop)  # (held weakly: a bound method)

    @property
    def previous(self):
        return self._work.previous

    @previous.setter
    def previous(self, value) -> None:
        self._work.previous = value

    def submit(self, generation: int, job: Any) -> None:
        """Build ``job`` (called on the executor thread, or before it spins)."""
        if self._poll is None:  # made once, then cancelled and reset: each timer made leaks ~80 B in rcl
            self._poll = self._node.create_timer(POLL_PERIOD, self.deliver_finished, clock=STEADY)
        elif self._poll.is_canceled():
            self._poll.reset()
        if sys.getswitchinterval() > SWITCH_INTERVAL:
            sys.setswitchinterval(SWITCH_INTERVAL)
        self._work.submit(generation, job, self._name)

    @property
    def cancelled(self) -> int:
        """How many builds were cancelled."""
        return self._work.cancelled

    def build_here(self, generation: int, job: Any) -> None:
        """Build ``job`` on this (the executor) thread and deliver it: for quick builds.
        The worker's jobs, older, are superseded: dropped, and its build cancelled."""
        self._work.stop()
        try:
            result = self.previous = self._work.build(job, self.previous)
        except Exception as error:  # noqa: BLE001  (reported to the node like a worker's)
            result = Failed(error)
        self._deliver(generation, result)

    def wait(self, timeout: float, still_wanted: Callable[[], bool]) -> bool:
        """Wait (on the caller's thread, before spinning) up to ``timeout`` s for a result
        and deliver it; stop early when ``still_wanted()`` turns false. True if delivered."""
        deadline = time.monotonic() + timeout
        while not self._work.done.wait(timeout=0.05):
            if time.monotonic() > deadline or not still_wanted():
                return False
        self.deliver_finished()
        return True

    def deliver_finished(self) -> None:
        """On the executor thread: deliver the newest result, if any; the poll ends with the work."""
        work = self._work
        with work.lock:
            finished, work.finished = work.finished, None
            work.done.clear()
            idle = not work.busy
        if idle and self._poll is not None:
            self._poll.cancel()
        if finished is not None:
            self._deliver(*finished)
