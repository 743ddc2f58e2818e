"""The benchmarks' receiving end: a subscription's messages taken as they arrive, with their times."""

from __future__ import annotations

import threading
import time


class Receiver(threading.Thread):
    """Takes the torque messages as they arrive, with their times, in a tight loop of its own.

    It waits on the subscription alone and takes every message ready (no executor): per
    message (input stamp, output's source time at the node, its DDS reception time here,
    the time taken here), all in ns of the system clock, and the output's sequence number
    at the node's writer (a gap: the node published it and it was lost on the way here).
    """

    def __init__(self, subscription, context):
        super().__init__(daemon=True)
        self.subscription, self.context = subscription, context
        self.records: list[tuple[int, int, int, int, int]] = []
        self.last_arrival = time.monotonic()
        self.stopping = threading.Event()

    def run(self) -> None:
        from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

        sub, records = self.subscription, self.records
        wait_set = _rclpy.WaitSet(1, 0, 0, 0, 0, 0, self.context.handle)
        while not self.stopping.is_set():
            wait_set.clear_entities()
            wait_set.add_subscription(sub.handle)
            wait_set.wait(10_000_000)  # ns
            while True:
                with sub.handle:
                    taken = sub.handle.take_message(sub.msg_type, sub.raw)
                if taken is None:
                    break
                now = time.time_ns()
                msg, info = taken
                stamp = msg.header.stamp
                records.append(
                    (
                        stamp.sec * 1_000_000_000 + stamp.nanosec,
                        info["source_timestamp"],
                        info["received_timestamp"],
                        now,
                        info["publication_sequence_number"] or 0,
                    )
                )
                self.last_arrival = time.monotonic()

    def stop(self) -> None:
        self.stopping.set()
        self.join(timeout=5)
