"""The ROS 2 nodes, one room each (``nodes/<name>/``): ``node.py`` (the Node and its
main(): messages in, calls to the core, messages out) and, where it has them, the node's
settings and helpers of its own. May import ``ros``, ``core``, ``identification``, ``sim``;
never another node (what several nodes share goes to ``ros``), never ``tools``.
"""

import importlib
import os
import signal


def start(module: str) -> None:
    """The console script of a node: import ``module`` and run its main(). Ctrl-C while
    Python is still importing it (NumPy, rclpy, ... take a moment) ends quietly, exit 0:
    the stop asked for, with no traceback of an import cut short; from main() on, the
    node's own handling takes over (ros.runtime.spin.run)."""

    def quiet(signum, frame):  # noqa: ARG001
        os._exit(0)

    previous = signal.signal(signal.SIGINT, quiet)
    try:
        main = importlib.import_module(module).main
    finally:
        signal.signal(signal.SIGINT, previous)
    main()
