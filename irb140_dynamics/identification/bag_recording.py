"""One topic written to a new ROS 2 bag (.mcap) as its messages come, and when that recording
is complete: ``duration`` s after the first message, or ``tail`` s after the end of the last
motion sent on a reference topic. Times are the receiver's clock in ns. No ROS here:
ros.recorder subscribes and hands each message in (as CDR bytes).
"""

from __future__ import annotations

import shutil
import time
from pathlib import Path

from irb140_dynamics.core.errors import counted
from irb140_dynamics.identification.recording import bag_connection, open_bag


class BagRecording:
    """The bag at ``out`` (new) of ``topic``; ``finished`` says why it is complete,
    ``failure`` why it cannot go on (one line)."""

    def __init__(self, out: Path, topic: str, duration: float, tail: float, reference: str | None = None):
        self.out, self.topic, self.duration, self.tail, self.reference = Path(out), topic, duration, tail, reference
        self.finished: str | None = None
        self.failure: str | None = None
        self.reference_end: int | None = None  # ns: where the last motion on the reference ends
        self.count, self.first, self.last = 0, None, None  # messages, receive times [ns]
        self._writer, self._connection = open_bag(self.out), None
        self.waiting_since = time.monotonic()

    def start(self, type_name: str) -> None:
        """The topic's messages are of ``type_name`` (e.g. sensor_msgs/msg/JointState)."""
        self._connection = bag_connection(self._writer, self.topic, type_name)

    def write(self, now: int, raw: bytes) -> None:
        """A message received at ``now`` written, unless the recording is over; a write that
        fails (a full disk) ends it."""
        if self.finished or self.failure:
            return
        if self.first is None:
            self.first = now
        elif self.check(now):
            return
        try:
            self._writer.write(self._connection, now, raw)
        except (OSError, ValueError) as error:
            self.failure = f"{self.out}: cannot write ({getattr(error, 'strerror', None) or error})"
            return
        self.count, self.last = self.count + 1, now

    def check(self, now: int) -> bool:
        """Is the recording complete at ``now``? Sets ``finished``."""
        if self.finished:
            return True
        if self.duration and self.first is not None and now - self.first >= self.duration * 1e9:
            self.finished = f"{self.duration:g} s after the first message"
        elif self.reference_end is not None and now >= self.reference_end + self.tail * 1e9:
            self.finished = f"{self.tail:g} s after the end of the motion on {self.reference}"
        return self.finished is not None

    def progress(self) -> str:
        """What is recorded so far, in a line."""
        if self._connection is None:
            return f"waiting for a publisher of {self.topic}: {time.monotonic() - self.waiting_since:.0f} s"
        goal = f" of {self.duration:g} s" if self.duration else ""
        return f"recording {self.topic}: {counted(self.count, 'message')}, {self._span():.1f} s{goal}"

    def close(self) -> str:
        """Close the bag (once: a bag half closed is unreadable); what it holds, in a line. A
        bag without a message is removed (the folder was new)."""
        self._writer.close()
        if self.count == 0:
            shutil.rmtree(self.out, ignore_errors=True)
            return f"no message came on {self.topic}: nothing written"
        return f"wrote {self.out}: {counted(self.count, 'message')} of {self.topic} over {self._span():.3f} s"

    def _span(self) -> float:
        return 0.0 if self.first is None else (self.last - self.first) * 1e-9
