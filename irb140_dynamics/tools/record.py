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
shows its progress on stderr, then prints what it wrote.

Never loses what it received: a signal, at any moment and however many, only asks it to
stop; the bag is then closed whole. Exit status 0 for a finished or requested stop; 1
with one line when it cannot record (nothing created when the arguments are wrong: DIR
exists or cannot be made, a bad topic name); 2 for a bad argument.
"""

from __future__ import annotations

import argparse
import signal
import sys
import time

from irb140_dynamics.tools.cli import Parser, ToolError, number, one_line, output_directory

DEFAULT_TOPIC = "/joint_states"  # as identification.recording's
PROGRESS_PERIOD = 2.0  # s between progress lines when stderr is not a terminal (0.2 on one)
DRAIN_TIME = 1.0  # s: after Ctrl-C, messages already received are written, for at most this long
DRAIN_QUIET = 0.05  # s: until none has come for this long


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
        from irb140_dynamics.tools import EARLY_SIGNALS

        self.signals: list[int] = EARLY_SIGNALS  # those that came while the tool was starting
        self.previous = {s: signal.signal(s, self._on_signal) for s in self.SIGNALS}

    def restore(self) -> None:
        """The handlers from before (main() called in a process that goes on); SIG_IGN when
        the tool is the program (Python restores the default ones as it exits)."""
        from irb140_dynamics.tools import AS_PROGRAM

        for s, handler in self.previous.items():
            signal.signal(s, signal.SIG_IGN if AS_PROGRAM else handler)

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
    from rclpy.expand_topic_name import expand_topic_name
    from rclpy.validate_full_topic_name import validate_full_topic_name

    from irb140_dynamics.ros.runtime.spin import tool_arguments

    try:
        args = parser().parse_args(tool_arguments(argv))
    except ValueError as error:  # rcl refused the ROS arguments
        raise ToolError(str(error)) from None
    for option, name in (("--topic", args.topic), ("--reference", args.reference)):
        if name is None:
            continue
        try:
            validate_full_topic_name(expand_topic_name(name, "record", "/"))
        except Exception as error:  # noqa: BLE001  (rclpy's InvalidTopicNameException and others)
            raise ToolError(f"{option} {name!r}: {str(error).splitlines()[0].split(', at /')[0]}") from None
    out = output_directory(args.out, must_be_new=True)
    if stop:
        _say("record: stopped before recording: nothing written")
        return 0
    return _spin(argv, args, out, stop)


def _spin(argv: list[str], args, out, stop: Stop) -> int:
    import rclpy
    from rclpy.impl.implementation_singleton import rclpy_implementation
    from rclpy.signals import SignalHandlerOptions

    from irb140_dynamics.ros.recorder import Recorder
    from irb140_dynamics.ros.runtime.spin import init_error

    try:
        rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    except rclpy_implementation.RCLError as error:
        raise ToolError(init_error(error)) from None
    recorder, summary, why = None, None, None
    try:
        try:
            recorder = Recorder(args.topic, out, args.duration, args.depth, args.reference, args.tail)
        except (ValueError, OSError) as error:
            raise ToolError(f"{args.out}: {getattr(error, 'strerror', None) or error}") from None
        try:
            why = _loop(recorder, stop)
        finally:  # whatever happened: the bag closed whole (signals only set flags meanwhile)
            try:
                summary = recorder.close()
            except (OSError, ValueError) as error:  # a full disk
                recorder.failure = recorder.failure or f"{args.out}: cannot close the bag ({error})"
            recorder.destroy_node()
    finally:
        rclpy.try_shutdown()
    print(f"stopped: {why}", file=sys.stderr, flush=True)
    if summary is not None:
        print(summary, flush=True)
    if recorder.failure:
        _say(f"record: error: {recorder.failure}")
        return 1
    return 0


def _loop(recorder, stop: Stop) -> str:
    """Spin until the recording is complete, fails or is stopped: why it ended."""
    executor = _executor(recorder)
    progress = _Progress()
    try:
        while not stop and not recorder.failure and not recorder.check() and recorder.context.ok():
            executor.spin_once(timeout_sec=0.1)
            progress(recorder.progress())
        if stop and not recorder.finished:  # what is queued was received before the signal
            deadline, count, quiet = time.monotonic() + DRAIN_TIME, -1, time.monotonic()
            while time.monotonic() < min(deadline, quiet + DRAIN_QUIET) and not recorder.failure:
                if recorder.count != count:
                    count, quiet = recorder.count, time.monotonic()
                executor.spin_once(timeout_sec=0.01)
    finally:
        progress.end()
        executor.shutdown()
    return recorder.failure or recorder.finished or ("interrupted" if stop else "the ROS context shut down")


def _executor(node):
    try:
        from rclpy.experimental import EventsExecutor

        executor = EventsExecutor(context=node.context)
    except (ImportError, OSError, ValueError):  # (it enables faulthandler: a stderr without a file fails)
        from rclpy.executors import SingleThreadedExecutor

        executor = SingleThreadedExecutor(context=node.context)
    executor.add_node(node)
    return executor


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
    sys.exit(main())
