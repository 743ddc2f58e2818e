"""main() of every node: start, spin, shut down cleanly; a bad start is one clear line."""

from __future__ import annotations

import sys
from typing import Callable

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.node import Node

from .params import check_parameter_files


def run(name: str, make_node: Callable[[], Node], args: list[str] | None = None) -> int:
    """Init rclpy, build the node, spin until Ctrl-C or shutdown; 0 on a clean exit.

    A model or parameter error at startup prints one line naming the bad field and
    returns 1 (no traceback).
    """
    args = sys.argv if args is None else args
    logger = rclpy.logging.get_logger(name)
    try:
        check_parameter_files(args)
        rclpy.init(args=args)
    except (ValueError, rclpy_implementation.RCLError) as error:
        logger.fatal(f"cannot start: {_one_line(error)}")
        return 1
    try:
        node = make_node()
    except ValueError as error:
        logger.fatal(f"cannot start: {_one_line(error)}")
        rclpy.try_shutdown()
        return 1
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


def _one_line(error: Exception) -> str:
    """rcl's messages carry ', at file:line' trails; keep the sentence."""
    return str(error).split(", at /")[0].replace("\n", " ")
