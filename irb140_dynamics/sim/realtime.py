"""Real-time pacing of a fixed-step simulation: which steps are due, and which ran late.

Step k (k = 1, 2, ...) is due at start + k * period (start: the first call, so that step 1 is
due then). A call at ``now`` runs every step due by then (half a period of grace for timer
jitter), catching up when a call came late. A step that runs more than one period after
it was due is *late*. When the schedule is behind by more than ``max_lag``, the steps in
between are *skipped* instead: the schedule moves on (simulated time then runs behind wall
time by the skipped steps) rather than racing through a burst of catch-up steps.
"""

from __future__ import annotations

import gc
import math
import os
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

SWITCH_INTERVAL = 1e-4  # s: Python's GIL switch interval while a loop runs


@dataclass
class StepSchedule:
    period: float  # s
    max_lag: float = 0.05  # s: behind by more than this, skip rather than catch up
    start: float | None = None  # s, the clock of ``due``'s ``now`` (monotonic)
    steps: int = 0  # steps run (handed out by ``due``)
    late: int = 0  # of them, run more than one period after they were due
    skipped: int = 0  # steps never run: the schedule moved on

    def __post_init__(self):
        if not (math.isfinite(self.period) and self.period > 0.0):
            raise ValueError(f"period: must be > 0, got {self.period}")

    def due(self, now: float) -> int:
        """How many steps to run at ``now`` (0 when the next is not yet due)."""
        if self.start is None:
            self.start = now - self.period
        count = math.floor((now - self.start) / self.period + 0.5) - self.steps
        if count <= 0:
            return 0
        behind = now - self.due_time(self.steps + 1)
        if behind > self.max_lag:
            self.skipped += count - 1
            self.start += (count - 1) * self.period
            count = 1
        # steps k of this batch with due_time(k) < now - period are late
        last_on_time = math.floor((now - self.period - self.start) / self.period)
        self.late += max(0, min(last_on_time, self.steps + count) - self.steps)
        self.steps += count
        return count

    def counts(self) -> dict[str, int]:
        """The counts /diagnostics reports, by name."""
        return {"steps": self.steps, "late_steps": self.late, "skipped_steps": self.skipped}

    def due_time(self, k: int) -> float:
        """When step k is due, on the clock of ``now``."""
        return self.start + k * self.period


class RealTimeLoop:
    """Calls ``step(k, t)`` for each step k as it falls due (t: its due time, monotonic), in a
    thread of its own that sleeps between steps: lighter than an executor's timer, whose
    every tick costs CPU in rclpy (docs/benchmarks.md, sim_node). An exception from ``step`` goes to ``on_error`` and the loop goes on."""

    def __init__(
        self,
        period: float,
        step: Callable[[int, float], None],
        on_error: Callable[[Exception], None],
        max_lag: float = 0.05,
    ):
        self.schedule = StepSchedule(period, max_lag)
        self._step, self._on_error = step, on_error
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._run, name="real_time_loop", daemon=True)

    def start(self, priority: int = 0) -> str | None:
        """Start stepping; ``priority`` > 0: the thread, and the calling one, run under
        SCHED_FIFO at that priority (1..99; Linux), as ros2_control's controller manager runs
        its loop. Returns why the priority was refused (no CAP_SYS_NICE or rtprio limit), None
        when granted or not asked."""
        # a thread that wants the GIL gets it within this (Python's default is a batch of late steps)
        sys.setswitchinterval(min(sys.getswitchinterval(), SWITCH_INTERVAL))
        # the objects alive now (modules, models, the node) are never scanned again: a full
        # garbage collection of a sim_node process then scans only what came after startup
        gc.freeze()
        self._thread.start()
        if priority <= 0:
            return None
        try:
            # the calling thread too (it runs the executor): the stepping thread needs the GIL,
            # and a holder of ordinary priority preempted by other processes would hold it up
            for thread_id in (self._thread.native_id, 0):
                os.sched_setscheduler(thread_id, os.SCHED_FIFO, os.sched_param(priority))
        except (OSError, AttributeError) as error:  # AttributeError: not Linux
            return str(error)
        return None

    def stop(self, timeout: float = 2.0) -> None:
        self._stopping.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout)

    def _run(self) -> None:
        schedule = self.schedule
        while not self._stopping.is_set():
            due = schedule.due(time.monotonic())
            for k in range(schedule.steps - due + 1, schedule.steps + 1):
                try:
                    self._step(k, schedule.due_time(k))
                except Exception as error:  # noqa: BLE001 - reported, and the loop must go on
                    self._on_error(error)
            time.sleep(max(0.0, schedule.due_time(schedule.steps + 1) - time.monotonic()))
