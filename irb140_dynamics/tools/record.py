"""record: a topic to a ROS 2 bag (.mcap), where `ros2 bag` is not installed.

    ros2 run irb140_dynamics record --out DIR [--topic /joint_states] [--duration S]
                                    [--ros-args -p use_sim_time:=true]

Writes DIR, a bag directory (metadata.yaml and DIR_0.mcap, as `ros2 bag record -o DIR`)
that `identify` and `ros2 bag` read, with every message of the topic from its first
publisher on. Stops after --duration seconds of the node's clock after the first message
(simulated time with use_sim_time), or at Ctrl-C; then prints what it wrote. Exit
status 0, or 1 with one line (DIR exists already, bad arguments).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from irb140_dynamics.identification.recording import DEFAULT_TOPIC
from irb140_dynamics.ros.recorder import DEFAULT_DEPTH, Recorder
from irb140_dynamics.ros.runtime.spin import run, tool_arguments


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="record", description=__doc__.split("\n\n")[0].split(": ", 1)[1])
    p.add_argument("--out", required=True, metavar="DIR", help="the bag directory to write (must not exist)")
    p.add_argument("--topic", default=DEFAULT_TOPIC, help=f"the topic (default {DEFAULT_TOPIC})")
    p.add_argument(
        "--duration",
        type=float,
        default=0.0,
        metavar="S",
        help="stop this long after the first message, node clock (default 0: at Ctrl-C)",
    )
    p.add_argument("--depth", type=int, default=DEFAULT_DEPTH, help=f"queue depth (default {DEFAULT_DEPTH})")
    return p


def main(argv=None) -> int:
    argv = sys.argv if argv is None else argv
    args = parser().parse_args(tool_arguments(argv))
    recorders = []

    def make_node() -> Recorder:
        recorders.append(Recorder(args.topic, Path(args.out), args.duration, args.depth))
        return recorders[-1]

    code = run("record", make_node, argv)
    if recorders:
        print(recorders[-1].close(), flush=True)
    return code


if __name__ == "__main__":
    sys.exit(main())
