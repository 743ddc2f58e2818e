"""main() of every node: start, spin, shut down cleanly; a bad start is one clear line."""

from __future__ import annotations

import gc
import re
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import rclpy
import rclpy.logging
from rclpy.executors import ExternalShutdownException
from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.node import Node
from rclpy.signals import (
    SignalHandlerOptions,
    get_current_signal_handlers_options,
    install_signal_handlers,
    uninstall_signal_handlers,
)
from rclpy.utilities import remove_ros_args

from irb140_dynamics.core.errors import one_line
from irb140_dynamics.ros.runtime.command_line import Usage, before_start

EXECUTORS = ("events", "single_threaded")


def tool_arguments(argv: list[str]) -> list[str]:
    """A tool's own command-line arguments: argv without the program and the ROS arguments
    (ValueError in one line if rcl refuses those)."""
    try:
        return remove_ros_args(argv)[1:]
    except rclpy_implementation.RCLError as error:
        raise ValueError(init_error(error)) from None


def run(
    name: str,
    make_node: Callable[[], Node],
    args: list[str] | None = None,
    executor: str = "events",
    usage: Callable[[], Usage] | None = None,
) -> int:
    """Init rclpy, build the node, spin until Ctrl-C or shutdown; 0 on a clean exit.

    Before ROS starts: ``--help`` prints ``usage()`` (0); a ROS argument outside
    ``--ros-args`` (2) or a params file that is missing, not a file or too large (1) is
    refused in one line (see command_line). A model or parameter error at startup prints
    one line naming the bad field and returns 1 (no traceback). Ctrl-C is the normal stop
    at any moment: 0, at most one line. ``executor``: see ``spin``.
    """
    args = sys.argv if args is None else args
    try:
        answered = before_start(name, args, usage)
        if answered is None:
            return _run(make_node, args, executor, rclpy.logging.get_logger(name))
    except KeyboardInterrupt:  # before the node's own handling, or a second while shutting down
        rclpy.try_shutdown()
        return 0
    code, text = answered
    if code == 0:
        sys.stdout.write(text)
    else:
        rclpy.logging.get_logger(name).fatal(text)
    return code


def _run(make_node: Callable[[], Node], args: list[str], executor: str, logger) -> int:
    node, code = _start(make_node, args, logger)
    if node is None:
        rclpy.try_shutdown()
        return code
    try:
        spin(node, executor)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


INTERRUPTED = "interrupted (Ctrl-C) before the node was ready"


def freeze_startup_objects() -> None:
    """Keep the objects of startup (modules, rclpy, NumPy, the model: some 40,000) out of
    the garbage collector's full passes: a pass over them all is a stall in which a 1 kHz
    stream can overflow its queue (bench/bench_nodes.py, the run with parameter changes). Objects made later are collected as ever."""
    gc.collect()
    gc.freeze()


def _start(make_node: Callable[[], Node], args: list[str], logger) -> tuple[Node | None, int]:
    """(the node, 0), or (None, exit code) after one line: 1 and FATAL when rcl refused the
    arguments or a parameter is bad (ValueError); 0 when Ctrl-C came first (rclpy then
    shuts the context down, and the next rclpy call of the half-built node fails, or
    KeyboardInterrupt is raised)."""
    try:
        try:
            with quiet_rcl():
                rclpy.init(args=args)
        except rclpy_implementation.UnknownROSArgsError as error:
            logger.fatal(f"cannot start: rcl does not know the ROS arguments {error} (see --help)")
            return None, 1
        except rclpy_implementation.RCLError as error:
            logger.fatal(f"cannot start: {init_error(error)}")
            return None, 1
        try:
            return make_node(), 0
        except Exception as error:  # noqa: BLE001  (sorted here: ours, or Ctrl-C half-way)
            if rclpy.ok() and not isinstance(error, ValueError):
                raise
            why = f"cannot start: {one_line(error)}" if rclpy.ok() else INTERRUPTED
    except KeyboardInterrupt:
        why = INTERRUPTED
    # out of the except blocks: the half-built node is gone with the traceback, and with it
    # its /rosout publisher, which would complain of the shut-down context
    gc.collect()
    if why == INTERRUPTED:
        logger.info(why)
        return None, 0
    logger.fatal(why)
    return None, 1


@contextmanager
def quiet_rcl() -> Iterator[None]:
    """rcl's own log of a refused argument ("Failed to parse global arguments") held back:
    the refusal is said once, in the node's FATAL line."""
    rcl = rclpy.logging.get_logger("rcl")
    level = rcl.get_effective_level()
    rcl.set_level(rclpy.logging.LoggingSeverity.FATAL)
    try:
        yield
    finally:
        rcl.set_level(level)


def spin(node: Node, executor: str = "events") -> None:
    """Run the node's callbacks until its context shuts down or Ctrl-C.

    ``events``: rclpy's EventsExecutor, when this rclpy has it: under half the CPU per
    message of the default executor (bench/bench_nodes.py). Driven by spin_once: its
    spin() in the 7.1 wheels busy-loops without running callbacks; Ctrl-C is read between
    spin_once calls (``ctrl_c_as_a_flag``). ``single_threaded``:
    rclpy.spin, the default SingleThreadedExecutor. The objects made so far are frozen
    first (``freeze_startup_objects``).
    """
    freeze_startup_objects()
    try:
        from rclpy.experimental import EventsExecutor
    except ImportError:
        executor = "single_threaded"
    if executor == "single_threaded":
        rclpy.spin(node)
        return
    events = EventsExecutor(context=node.context)
    events.add_node(node)
    with ctrl_c_as_a_flag() as interrupted:
        try:
            while node.context.ok() and not interrupted:
                events.spin_once(timeout_sec=WAKE_PERIOD)
        finally:
            events.shutdown()


WAKE_PERIOD = 0.1  # s: the longest spin_once waits, so the longest a Ctrl-C waits to be seen


@contextmanager
def ctrl_c_as_a_flag() -> Iterator[list]:
    """Ctrl-C (SIGINT) appends to the list yielded instead of raising KeyboardInterrupt; a
    second Ctrl-C raises it (a callback that hangs can still be cut).

    Python raises KeyboardInterrupt at the next line of Python that runs, which under the
    EventsExecutor may be inside rclpy's C++: building a message (its __init__ is Python)
    then fails as "RuntimeError: Unable to convert call argument '0' to Python object", or
    a callback is cut half-way and logged FATAL. The flag is read between spin_once calls
    instead. rclpy's own handlers are set aside meanwhile (SIGTERM keeps rclpy's: it shuts
    the context down) and put back after. Outside the main thread the list stays empty.
    """
    interrupted: list = []
    if threading.current_thread() is not threading.main_thread():
        yield interrupted
        return

    def on_sigint(*_) -> None:
        if interrupted:
            raise KeyboardInterrupt
        interrupted.append(True)

    options = get_current_signal_handlers_options()
    uninstall_signal_handlers()  # rclpy chains to the handler before it: unchain it first
    previous = signal.signal(signal.SIGINT, on_sigint)
    if options in (SignalHandlerOptions.SIGTERM, SignalHandlerOptions.ALL):
        install_signal_handlers(SignalHandlerOptions.SIGTERM)
    try:
        yield interrupted
    finally:
        uninstall_signal_handlers()
        signal.signal(signal.SIGINT, previous)
        install_signal_handlers(options)


_PARAMS_FILE_ERROR = re.compile(
    r"params file: '--params-file (?P<path>.+?)'\. Error: (?P<reason>.+?)"
    r"(?:(?: at line_num| near line|\. Error at line) (?P<line>\d+))?\s*(?:, at /|$)"
)


def init_error(error: Exception) -> str:
    """rcl's refusal of the arguments in one line; for a params file, the line it refuses."""
    text = str(error)
    found = _PARAMS_FILE_ERROR.search(text)
    if not found:
        return text.split(", at /")[0]
    path, reason, line = found["path"], found["reason"].rstrip(". "), found["line"]
    if line is None or int(line) < 1:  # rcl gives line 0 for some errors (a binary file)
        return f"{path}: {reason}"
    source = _line(path, int(line))
    hint = "; write every number of a list as a double, e.g. 0.0 not 0" if "same type" in reason else ""
    return f"{path}:{line}: {reason} in `{source}`{hint}"


def _line(path: str, number: int) -> str:
    """Line ``number`` of the file, undecodable bytes shown as \\xNN (a binary file)."""
    try:
        with open(path, encoding="utf-8", errors="backslashreplace") as stream:
            return stream.read().splitlines()[number - 1].strip()
    except (OSError, IndexError):
        return "?"
