"""record: a topic to a ROS 2 bag (.mcap), where `ros2 bag` is not installed.

    irb140-record --out DIR [--topic /joint_states] [--duration S]
                  [--reference /id_node/reference [--tail S]] [--ros-args -p use_sim_time:=true]
    (or: ros2 run irb140_dynamics record ..., python -m irb140_dynamics.tools.record ...)

Writes DIR, a bag directory (metadata.yaml and DIR_0.mcap, as `ros2 bag record -o DIR`)
that `identify` and `ros2 bag` read, with every message of the topic from its first
publisher on, stamped with the node's clock (simulated time with use_sim_time). Stops by
itself --duration seconds after the first message recorded, or --tail seconds after the
motion last sent on --reference ends (a JointTrajectory, as id_node follows it: from its
header stamp, or from its arrival when unstamped), or at Ctrl-C (SIGINT, SIGTERM, SIGHUP);
shows its progress on stderr, then prints what it wrote. While the topic has no publisher,
after 3 s a line on stderr names the topics that have one, and it waits on (the publisher
may start later). When no message came, no bag is left ("nothing written").

Never loses what it received: a signal, at any moment and however many, only asks it to
stop; the bag is then closed whole. Exit status 0 for a finished or requested stop; 1
with one line when it cannot record (nothing created when the arguments are wrong: DIR
exists or cannot be made, a bad topic name); 2 for a bad argument.
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m: the entry first, before the heavy imports
    from irb140_dynamics.entry import RECORDER, start

    start("record", RECORDER)

import argparse
import signal
import sys
import time

from irb140_dynamics.entry import take_noted_signals
from irb140_dynamics.tools.cli import Parser, ToolError, number, one_line, output_directory

DEFAULT_TOPIC = "/joint_states"  # as identification.recording's
PROGRESS_PERIOD = 2.0  # s between progress lines when stderr is not a terminal (0.2 on one)


def parser() -> Parser:
    p = Parser(
        prog="record",
        description=__doc__.split("\n\n")[0].split(": ", 1)[1],
        epilog="\n\n".join(__doc__.split("\n\n")[2:]),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--out", required=True, metavar="DIR", help="the bag directory to write (must not exist)")
    p.add_argument("--topic", default=DEFAULT_TOPIC, help=f"the topic (default {DEFAULT_TOPIC})")
    p.add_argument(
        "--duration",
        type=number(0.0, 1e7),
        default=0.0,
        metavar="S",
        help="stop this long after the first message, node clock (default 0: no limit)",
    )
    p.add_argument(
        "--reference",
        metavar="TOPIC",
        help="a JointTrajectory topic (e.g. /id_node/reference): stop --tail s after its motion ends",
    )
    p.add_argument("--tail", type=number(0.0, 1e6), default=1.0, metavar="S", help="see --reference (default 1 s)")
    p.add_argument("--depth", type=number(1, 1_000_000, integer=True), default=1000, help="queue depth (default 1000)")
    return p


class Stop:
    """SIGINT, SIGTERM and SIGHUP only ask to stop (never raise): the bag is always closed whole."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

    def __init__(self):
        self.signals: list[int] = []
        self.previous = {s: signal.signal(s, self._on_signal) for s in self.SIGNALS}
        self.signals[:0] = take_noted_signals()  # those that came while the tool was starting

    def restore(self) -> None:
        """The handlers from before (the entry's, when the tool is the program: it ignores
        the signals once main() has returned)."""
        for s, handler in self.previous.items():
            signal.signal(s, handler)

    def _on_signal(self, signum, _frame) -> None:
        self.signals.append(signum)

    def __bool__(self) -> bool:
        return bool(self.signals)


def main(argv: list[str] | None = None) -> int:
    stop = Stop()  # first: a Ctrl-C during the imports below is a request too
    argv = sys.argv if argv is None else list(argv)
    try:
        return _record(argv, stop)
    except ToolError as error:
        _say(f"record: error: {error}")
        return 1
    except SystemExit as exit_:  # argparse: --help, a bad argument (its line printed)
        return exit_.code if isinstance(exit_.code, int) else 0
    except Exception as error:  # noqa: BLE001  (a defect of ours: the bag is closed, then one line)
        _say(f"record: internal error: {type(error).__name__}: {error}")
        return 1
    finally:
        stop.restore()


def _record(argv: list[str], stop: Stop) -> int:
    try:
        from irb140_dynamics.ros.recorder import CannotRecord, record, topic_error
        from irb140_dynamics.ros.runtime.spin import tool_arguments
    except ImportError as error:  # record subscribes through ROS 2: rclpy and the messages
        raise ToolError(
            f"needs ROS 2 Jazzy's rclpy ({error.name} cannot be imported: see the README's set-up)"
        ) from None

    try:
        args = parser().parse_args(tool_arguments(argv))
    except ValueError as error:  # rcl refused the ROS arguments
        raise ToolError(str(error)) from None
    for option, name in (("--topic", args.topic), ("--reference", args.reference)):
        if name is not None and (reason := topic_error(name)) is not None:
            raise ToolError(f"{option} {name!r}: {reason}")
    out = output_directory(args.out, must_be_new=True)
    if stop:
        _say("record: stopped before recording: nothing written")
        return 0
    try:
        why, summary, failure = record(argv, args, out, stop, _Progress())
    except CannotRecord as error:
        raise ToolError(str(error)) from None
    print(f"stopped: {why}", file=sys.stderr, flush=True)
    if summary is not None:
        print(summary, flush=True)
    if failure:
        _say(f"record: error: {failure}")
        return 1
    return 0


class _Progress:
    """A progress line on stderr: redrawn on a terminal, else one every PROGRESS_PERIOD s."""

    def __init__(self):
        self.terminal = sys.stderr.isatty()
        self.period = 0.2 if self.terminal else PROGRESS_PERIOD
        self.last = time.monotonic()
        self.drawn = False

    def __call__(self, text: str) -> None:
        now = time.monotonic()
        if now - self.last < self.period:
            return
        self.last = now
        sys.stderr.write(f"\r{text}\x1b[K" if self.terminal else f"{text}\n")
        sys.stderr.flush()
        self.drawn = self.terminal

    def end(self) -> None:
        if self.drawn:
            sys.stderr.write("\n")
            self.drawn = False


def _say(text: str) -> None:
    print(one_line(text), file=sys.stderr, flush=True)


if __name__ == "__main__":
    from irb140_dynamics.entry import finish

    finish(main)
