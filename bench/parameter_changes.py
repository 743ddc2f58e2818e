"""A stream of parameter changes to a node under test, from a DDS participant of its own.

``ParameterChanger`` sets one parameter (``payload.mass`` by default, a new value each time,
so that id_node builds a new model for every change) every ``period`` seconds through the
standard SetParameters service, as `ros2 param set` would, and times each reply.
"""

from __future__ import annotations

import threading
import time

import numpy as np
from common import set_priority

REPLY_TIMEOUT = 5.0  # s
SERVICES_TIMEOUT = 30.0  # s, for the node's parameter services to appear


class ParameterChanger(threading.Thread):
    """Sets ``name`` on the node ``node_name`` (fully qualified) every ``period`` s once started."""

    def __init__(
        self, node_name: str, period: float, name: str = "payload.mass", first: float = 1.0, step: float = 0.001
    ):
        super().__init__(daemon=True)
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from rclpy.parameter_client import AsyncParameterClient

        self.period, self.name, self.first, self.step = period, name, first, step
        self.context = Context()
        rclpy.init(context=self.context)
        self.node = Node(f"bench_changer_{node_name.strip('/').replace('/', '_')}", context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.client = AsyncParameterClient(self.node, node_name)
        if not self.client.wait_for_services(timeout_sec=SERVICES_TIMEOUT):
            self.close()
            raise RuntimeError(f"{node_name}: no parameter services within {SERVICES_TIMEOUT:g} s")
        self.replies: list[float] = []  # s, per accepted change
        self.refused: list[str] = []
        self.unanswered = 0
        self.stopping = threading.Event()

    def run(self) -> None:
        from rclpy.parameter import Parameter

        set_priority(0)  # started by the benchmark's real-time publishing thread: not real-time itself
        start = time.monotonic()
        k = 0
        while not self.stopping.is_set():
            value = self.first + self.step * (k % 1000)
            sent = time.monotonic()
            future = self.client.set_parameters([Parameter(self.name, value=value)])
            self.executor.spin_until_future_complete(future, timeout_sec=REPLY_TIMEOUT)
            if not future.done():
                self.unanswered += 1
            else:
                result = future.result().results[0]
                if result.successful:
                    self.replies.append(time.monotonic() - sent)
                else:
                    self.refused.append(result.reason)
            k += 1
            self.stopping.wait(max(0.0, start + k * self.period - time.monotonic()))

    def stop(self) -> dict:
        """Stop, and the figures: changes made, refused, unanswered; reply times (ms)."""
        self.stopping.set()
        self.join(timeout=REPLY_TIMEOUT + 1)
        self.close()
        ms = np.array(self.replies) * 1e3
        reply = (
            {"p50": float(np.percentile(ms, 50)), "p99": float(np.percentile(ms, 99)), "max": float(ms.max())}
            if ms.size
            else {"p50": None, "p99": None, "max": None}
        )
        return {
            "parameter": self.name,
            "period_s": self.period,
            "accepted": len(self.replies),
            "refused": len(self.refused),
            "first_refusal": self.refused[0] if self.refused else None,
            "unanswered": self.unanswered,
            "reply_ms": reply,
        }

    def close(self) -> None:
        import rclpy

        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)
