"""Run a node as its own process, the way `ros2 run` would, with a time limit."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

from .paths import ROOT


def start(command: list[str], env: dict | None = None) -> subprocess.Popen:
    environment = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1", **(env or {})}
    return subprocess.Popen(command, env=environment, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def module_command(module: str, *ros_args: str) -> list[str]:
    command = [sys.executable, "-m", module]
    return command + ["--ros-args", *ros_args] if ros_args else command


def run_to_exit(command: list[str], env: dict | None = None, timeout: float = 60.0) -> tuple[int, str]:
    """(exit code, output) of a node that is expected to stop by itself."""
    process = start(command, env)
    try:
        output, _ = process.communicate(timeout=timeout)
    finally:
        process.kill()
    return process.returncode, output


def run_until_ready(command: list[str], env: dict | None = None, timeout: float = 60.0) -> tuple[int, str]:
    """Start a node, wait for its 'ready' line, stop it with Ctrl-C: (exit code, output)."""
    process = start(command, env)
    lines = []
    deadline = time.monotonic() + timeout
    try:
        os.set_blocking(process.stdout.fileno(), False)
        while time.monotonic() < deadline and not any("ready" in line for line in lines):
            line = process.stdout.readline()
            if line:
                lines.append(line)
            elif process.poll() is not None:
                break
            else:
                time.sleep(0.05)
        process.send_signal(signal.SIGINT)
        rest, _ = process.communicate(timeout=20)
        lines.append(rest or "")
    finally:
        process.kill()
    return process.returncode, "".join(lines)
