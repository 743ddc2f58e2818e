"""Lockstep stepping: the simulation steps once per command, and its time is the steps' count.

Instead of stepping in real time, a lockstep simulation publishes state k (simulated time
k * period) and waits for the command computed from it; that command is applied for one
period, giving state k + 1. The result then depends neither on the machine's load nor on
how fast the controller answers: a slow answer only slows simulated time down.

A lost message must not stall the loop: with no command for a timeout the last state is
due to be published again (it never steps without a command). The timeout is counted in
ticks of a periodic timer (``TICKS`` per timeout) rather than read off a clock: after a
stall of the simulation's own process (a busy machine) a timer fires once, not ``TICKS``
times. On a busy machine a state is still published again now and then while its answer
is only late, and then gets two answers. A deterministic controller (the same state at
the same time gives the same command) answers both alike: after a state published again,
the command after the first step is dropped as that duplicate when it equals the first
(bit for bit), else the count goes on. Without that, the second answer would be applied to
the next state, and every command after it one step late. A genuine answer equal to the
last command (the arm held still, and the command not depending on time) is dropped too:
the loop then waits for the next timeout, and after a timeout that followed a drop no
command is taken for a duplicate (else a held arm would wait a timeout every step). No
ROS here: sim_node publishes what this says.
"""

from __future__ import annotations

import math

import numpy as np

TICKS = 5  # timer ticks per timeout


class LockstepClock:
    """Simulated time of a lockstep simulation, and when its last state is due again."""

    def __init__(self, period: float):
        if not (math.isfinite(period) and period > 0.0):
            raise ValueError(f"period: must be > 0, got {period}")
        self.period = period
        self.steps = 0  # k: the state published last is state k
        self.republished = 0  # times the last state was published again
        self.duplicates = 0  # commands dropped as second answers to a state published again
        self._idle_ticks = 0  # timer ticks since the last step (or publication again)
        self._last: np.ndarray | None = None  # the command of the last step
        self._watch = 0  # 2: published again; 1: stepped since, the next command may be a duplicate
        self._dropped = False  # the last command was dropped as a duplicate

    @property
    def time(self) -> float:
        """Simulated time of state k [s]."""
        return self.steps * self.period

    @property
    def stamp(self) -> int:
        """Simulated time of state k [ns]: exactly k periods, whatever k."""
        return round(self.steps * self.period * 1e9)

    def counts(self) -> dict[str, int]:
        """The counts /diagnostics reports, by name."""
        return {"steps": self.steps, "republished": self.republished, "duplicates_dropped": self.duplicates}

    def accept(self, command: np.ndarray) -> bool:
        """Step on ``command``? False (counted) for the duplicate answer to a state published again."""
        self._dropped = False
        if self._watch == 1:
            self._watch = 0
            if np.array_equal(command, self._last):
                self.duplicates += 1
                self._dropped = True
        return not self._dropped

    def step(self, command: np.ndarray) -> None:
        """``command`` applied: now at state k + 1."""
        self.steps += 1
        self._idle_ticks = 0
        self._last = command
        self._watch = max(0, self._watch - 1)

    def tick(self) -> bool:
        """A timer tick (TICKS a timeout); True (and counted) when the last state has gone
        a timeout, TICKS ticks, without a command."""
        self._idle_ticks += 1
        if self._idle_ticks < TICKS:
            return False
        self._idle_ticks = 0
        self.republished += 1
        self._watch = 0 if self._dropped else 2
        return True
