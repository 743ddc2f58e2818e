"""main() of every node, as in ros2/examples: init, make the node, spin, shut down.

A bad start is one line (FATAL, exit 1, no traceback); Ctrl-C is the normal stop at any
moment (exit 0, at most one line).
"""

from __future__ import annotations

import gc
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import rclpy
import rclpy.logging
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions as Options
from rclpy.signals import get_current_signal_handlers_options, install_signal_handlers, uninstall_signal_handlers
from rclpy.utilities import remove_ros_args

from irb140_dynamics.core.errors import one_line
from irb140_dynamics.core.io.params_file import rcl_refusal
from irb140_dynamics.node_help import Usage
from irb140_dynamics.ros.runtime.command_line import before_start

EXECUTORS = ("events", "single_threaded")
INTERRUPTED = "interrupted (Ctrl-C) before the node was ready"
WAKE_PERIOD = 0.1  # s: the longest spin_once waits, so the longest a Ctrl-C waits to be seen


def tool_arguments(argv: list[str]) -> list[str]:
    """A tool's own arguments: argv without the program and the ROS arguments (ValueError
    in one line if rcl refuses those)."""
    try:
        return remove_ros_args(argv)[1:]
    except rclpy_implementation.RCLError as error:
        raise ValueError(rcl_refusal(str(error))) from None


def run(
    name: str,
    make_node: Callable[[], Node],
    args: list[str] | None = None,
    executor: str = "events",
    usage: Callable[[], Usage] | None = None,
) -> int:
    """The node's exit status: 0 after ``--help`` (``usage()`` printed), Ctrl-C or shutdown;
    2 for a ROS argument outside ``--ros-args``; 1 for a params file or a parameter that is
    refused (see command_line). ``executor``: see ``spin``."""
    args = sys.argv if args is None else args
    logger = rclpy.logging.get_logger(name)
    try:
        answered = before_start(name, args, usage)
        if answered is not None:
            code, text = answered
            sys.stdout.write(text) if code == 0 else logger.fatal(text)
            return code
        node = _start(make_node, args, logger)
        if isinstance(node, int):
            rclpy.try_shutdown()
            return node
        try:
            spin(node, executor)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        finally:
            node.destroy_node()
            rclpy.try_shutdown()
    except KeyboardInterrupt:  # before the node was made, or a second one while shutting down
        rclpy.try_shutdown()
    return 0


def _start(make_node: Callable[[], Node], args: list[str], logger) -> Node | int:
    """rclpy started and the node made; else the exit status, after one line. Ctrl-C while
    the node is made shuts the context down: its next rclpy call fails, or it is cut."""
    why = INTERRUPTED
    try:
        try:
            with quiet_rcl():
                rclpy.init(args=args)
        except rclpy_implementation.UnknownROSArgsError as error:
            why = f"cannot start: rcl does not know the ROS arguments {error} (see --help)"
        except rclpy_implementation.RCLError as error:
            why = f"cannot start: {rcl_refusal(str(error))}"
        else:
            try:
                return make_node()
            except Exception as error:  # noqa: BLE001  (ours, a ValueError; or cut by Ctrl-C)
                if rclpy.ok() and not isinstance(error, ValueError):
                    raise
                if rclpy.ok():
                    why = f"cannot start: {one_line(error)}"
    except KeyboardInterrupt:
        pass
    # out of the except blocks: the half-built node is collected, and with it its /rosout
    # publisher, which would complain of the shut-down context
    gc.collect()
    if why == INTERRUPTED:
        logger.info(why)
        return 0
    logger.fatal(why)
    return 1


@contextmanager
def quiet_rcl() -> Iterator[None]:
    """rcl's own log of a refused argument held back: the node's FATAL line says it once."""
    rcl = rclpy.logging.get_logger("rcl")
    level = rcl.get_effective_level()
    rcl.set_level(rclpy.logging.LoggingSeverity.FATAL)
    try:
        yield
    finally:
        rcl.set_level(level)


def spin(node: Node, executor: str = "events") -> None:
    """Run the node's callbacks until its context shuts down or Ctrl-C.

    ``events``: rclpy's EventsExecutor, where this rclpy has it (under half the CPU per
    message of the default executor, bench/bench_nodes.py); ``single_threaded``: rclpy's
    SingleThreadedExecutor. Either is driven by spin_once (the EventsExecutor's spin() in the
    7.1 wheels busy-loops) with Ctrl-C read between calls (``ctrl_c_as_a_flag``). The objects
    of startup (modules, rclpy, NumPy, the model: some 40,000) are frozen out of the garbage
    collector's full passes first: a pass over them all is a stall in which a 1 kHz stream
    can overflow its queue.
    """
    gc.collect()
    gc.freeze()
    try:
        from rclpy.experimental import EventsExecutor
    except ImportError:
        executor = "single_threaded"
    kind = EventsExecutor if executor == "events" else SingleThreadedExecutor
    spinner = kind(context=node.context)
    spinner.add_node(node)
    with ctrl_c_as_a_flag() as interrupted:
        try:
            while node.context.ok() and not interrupted:
                spinner.spin_once(timeout_sec=WAKE_PERIOD)
        finally:
            spinner.shutdown()


@contextmanager
def ctrl_c_as_a_flag() -> Iterator[list]:
    """Ctrl-C appends to the list yielded instead of raising; a second Ctrl-C raises
    KeyboardInterrupt (a callback that hangs can still be cut).

    Raised at the next line of Python, KeyboardInterrupt may strike inside rclpy's C++
    (building a message fails as "Unable to convert call argument '0'") or cut a callback
    half-way. rclpy's handlers are set aside meanwhile (SIGTERM keeps rclpy's: it shuts the
    context down) and put back after. Outside the main thread the list stays empty.
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
    if options in (Options.SIGTERM, Options.ALL):
        install_signal_handlers(Options.SIGTERM)
    try:
        yield interrupted
    finally:
        uninstall_signal_handlers()
        signal.signal(signal.SIGINT, previous)
        install_signal_handlers(options)
