"""sim_node's push on the flange: the last ~/external_wrench, held until a new one or a timeout.

Subscribes   ~/external_wrench   geometry_msgs/WrenchStamped: force [N] and torque [N m] about
                                 the flange origin, in the axes ``header.frame_id`` names, the
                                 tip link (``flange`` for a model of parameters) or the base
                                 link (``base_link``; a URDF's: its chain's links); applied to
                                 the flange body in MuJoCo from the next step on

A wrench is held (zero-order) until the next, and let go once older than command_timeout
(0: never), like the commands: on the monotonic clock in real time, on simulated time in
lockstep. A wrench with another frame, NaN, inf or more than ros.messages.wrench's
MAX_FORCE / MAX_TORQUE is dropped, counted and warned about, never applied; the one held
before stays.
"""

from __future__ import annotations

import numpy as np
from geometry_msgs.msg import WrenchStamped

from irb140_dynamics.ros.messages.wrench import read_wrench


class HeldWrench:
    """The wrench in force and the time it came [ns, the node's step clock]."""

    def __init__(self):
        self._held: tuple[int, np.ndarray, str] | None = None
        self.timed_out = 0

    def receive(self, msg: WrenchStamped, links: tuple[str, str], now: int) -> None:
        """Hold the message's wrench from ``now`` on, or BadMessage (the one held stays)."""
        values, frame = read_wrench(msg, links)
        self._held = (now, values, frame)

    def clear(self) -> None:
        self._held = None

    def current(self, now: int, timeout: float) -> tuple[np.ndarray | None, str]:
        """(wrench, frame) for a step at ``now`` [ns]: the held one while fresh, else (None, 'base')."""
        if self._held is None:
            return None, "base"
        received, values, frame = self._held
        if timeout > 0.0 and now - received > timeout * 1e9:
            self._held = None
            self.timed_out += 1
            return None, "base"
        return values, frame
