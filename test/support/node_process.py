"""Run a node as its own process, the way `ros2 run` would, with a time limit."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

from .hang_report import hang_report
from .paths import ROOT

TIMEOUT = 30.0  # s, a process start included


def start(command: list[str], env: dict | None = None) -> subprocess.Popen:
    environment = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1", **(env or {})}
    return subprocess.Popen(command, env=environment, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def console_script(name: str, *arguments: str) -> list[str]:
    """The executable ``name`` as its console script runs it (irb140_dynamics.programs)."""
    return [sys.executable, "-c", f"from irb140_dynamics.programs import {name}; {name}()", *arguments]


def module_command(module: str, *ros_args: str) -> list[str]:
    """``python -m module --ros-args ...``; a node's module (``irb140_dynamics.nodes.<name>.node``)
    as its console script runs it."""
    parts = module.split(".")
    if parts[:2] == ["irb140_dynamics", "nodes"] and parts[3:] == ["node"]:
        command = console_script(parts[2])
    else:
        command = [sys.executable, "-m", module]
    return command + ["--ros-args", *ros_args] if ros_args else command


def run_to_exit(command: list[str], env: dict | None = None, timeout: float = 60.0) -> tuple[int, str]:
    """(exit code, output) of a node that is expected to stop by itself."""
    process = start(command, env)
    try:
        output, _ = communicate(process, timeout)
    finally:
        process.kill()
    return process.returncode, output


def communicate(process: subprocess.Popen, timeout: float) -> tuple[str, str]:
    """``process.communicate``; if it has not ended in ``timeout`` s, an AssertionError that
    says what it and its children are doing (hang_report)."""
    try:
        return process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        raise AssertionError(f"{process.args} has not ended after {timeout:g} s:\n{hang_report(process.pid)}") from None


def wait_for_line(process: subprocess.Popen, text: str, lines: list[str], timeout: float = 60.0) -> bool:
    """Read the process's output into ``lines`` until a line with ``text`` (True), or the
    process ends or ``timeout`` passes (False)."""
    deadline = time.monotonic() + timeout
    os.set_blocking(process.stdout.fileno(), False)
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if line:
            lines.append(line)
            if text in line:
                return True
        elif process.poll() is not None:
            return False
        else:
            time.sleep(0.05)
    return False


def interrupt(process: subprocess.Popen, lines: list[str] | None = None, timeout: float = 20.0) -> tuple[int, str]:
    """Stop a process with Ctrl-C: (exit code, its output, after ``lines`` read before)."""
    try:
        process.send_signal(signal.SIGINT)
        rest, _ = communicate(process, timeout)
    finally:
        process.kill()
    return process.returncode, "".join(lines or []) + (rest or "")


def run_until_ready(command: list[str], env: dict | None = None, timeout: float = 60.0) -> tuple[int, str]:
    """Start a node, wait for its 'ready' line, stop it with Ctrl-C: (exit code, output)."""
    process = start(command, env)
    lines = []
    try:
        wait_for_line(process, "ready", lines, timeout)
    finally:
        code, output = interrupt(process, lines)
    return code, output


def one_fatal_line(code: int, output: str) -> str:
    """The one [FATAL] line of a node that refused to start (exit 1, no traceback)."""
    assert code == 1, output
    assert "Traceback" not in output, output
    fatal = [line for line in output.splitlines() if "[FATAL]" in line]
    assert len(fatal) == 1, output
    return fatal[0]


def handles_sigterm(pid: int) -> bool:
    """Has the process a handler of SIGTERM (an executable's, from irb140_dynamics.entry.start
    on: the moment its own code runs)?"""
    with open(f"/proc/{pid}/status") as status:
        caught = next(line for line in status if line.startswith("SigCgt:"))
    return bool(int(caught.split()[1], 16) >> (signal.SIGTERM - 1) & 1)
