"""The ROS 2 nodes, one room each (``nodes/<name>/``): ``node.py`` (the Node and its
main(): messages in, calls to the core, messages out) and, where it has them, the node's
settings and helpers of its own. May import ``ros``, ``core``, ``identification``, ``sim``;
never another node (what several nodes share goes to ``ros``), never ``tools``.
"""

import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def quiet_ctrl_c() -> Iterator[None]:
    """For a node's console script while it imports its node (NumPy, rclpy, ... take a
    moment): Ctrl-C then ends it quietly, exit 0, the stop asked for, with no traceback of
    an import cut short. From the node's main() on, its own handling takes over
    (ros.runtime.spin.run)."""

    def quiet(signum, frame):
        os._exit(0)

    previous = signal.signal(signal.SIGINT, quiet)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
