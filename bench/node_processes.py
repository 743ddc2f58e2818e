"""The benchmarked nodes as processes of their own: started as `ros2 run` would, stopped whatever happens.

Each process gets the checkout on PYTHONPATH and the benchmark's own DDS domain (localhost
discovery); its output goes to a temporary file, shown when it fails.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

from common import REPO
from machine_load import process_cpu_seconds

STARTUP_TIMEOUT = 30.0  # s, for a node process to start and match
QOS_DEPTH = 10  # id_node's qos.depth default; joint_states best effort as its qos.reliability default


def node_environment(domain_id: int) -> dict:
    """This process's environment for the nodes: the checkout importable, own DDS domain."""
    path = os.pathsep.join(p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p)
    return {
        **os.environ,
        "PYTHONPATH": path,
        "PYTHONUNBUFFERED": "1",
        "ROS_DOMAIN_ID": str(domain_id),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
    }


def isolated_domain(domain_id: int | None) -> tuple[int, dict]:
    """A DDS domain of the run's own (``domain_id``, else random in 50..99) on localhost, set
    for this process (call before rclpy.init); returns it and the nodes' environment."""
    domain_id = random.randint(50, 99) if domain_id is None else domain_id
    os.environ["ROS_DOMAIN_ID"] = str(domain_id)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    print(f"ROS_DOMAIN_ID={domain_id}", flush=True)
    return domain_id, node_environment(domain_id)


class NodeProcess:
    """A node in its own process, its output in a temporary file; stop() always ends it."""

    def __init__(self, command: list[str], env: dict):
        self.command = command
        self.log = tempfile.TemporaryFile(mode="w+")  # noqa: SIM115 (open for the process's life; closed in stop())
        self.process = subprocess.Popen(
            command, env=env, stdout=self.log, stderr=subprocess.STDOUT, text=True, preexec_fn=_die_with_parent
        )

    def alive(self) -> bool:
        return self.process.poll() is None

    def cpu_seconds(self) -> float:
        """User + system time of the process so far, all its threads."""
        return process_cpu_seconds(self.process.pid)

    def output(self, last: int = 15) -> str:
        self.log.flush()
        self.log.seek(0)
        return "".join(self.log.readlines()[-last:])

    def stop(self) -> None:
        if self.alive():
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout=5)
        self.log.close()

    def fail(self, what: str) -> RuntimeError:
        state = "running" if self.alive() else f"exited with {self.process.returncode}"
        return RuntimeError(f"{what} ({' '.join(self.command)}: {state}); its output:\n{self.output()}")


def _die_with_parent() -> None:
    """In the child: be killed if this process dies without stopping it (Linux)."""
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


MARKERS_OFF = "id_node_markers_off"  # a kind: id_node with markers.rate 0 (bench_markers.py)


def node_command(kind: str, executor: str, namespace: str, lean: bool = False, depth: int = QOS_DEPTH) -> list[str]:
    """id_node as `ros2 run` starts it (its main(): the events executor), or through
    relay_node.py (the relay, or id_node under another executor or without QoS event
    handlers, ``lean``); both with id_node's default QoS given explicitly."""
    ros_args = [
        "--ros-args",
        "-r",
        f"__ns:={namespace}",
        "-p",
        "qos.reliability:=best_effort",
        "-p",
        f"qos.depth:={depth}",
    ]
    if kind in ("id_node", MARKERS_OFF):
        ros_args += ["-p", "acceleration.mode:=differentiate"]
        if kind == MARKERS_OFF:
            ros_args += ["-p", "markers.rate:=0"]
        if executor == "events" and not lean:
            return [sys.executable, "-c", "from irb140_dynamics.programs import id_node; id_node()", *ros_args]
    lean_flag = ["--no-event-handlers"] if lean else []
    return [sys.executable, str(REPO / "bench" / "relay_node.py"), kind, "--executor", executor, *lean_flag, *ros_args]


def wait_for(condition: Callable[[], bool], timeout: float, process: NodeProcess, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if not process.alive() or time.monotonic() > deadline:
            raise process.fail(f"{what}: not within {timeout:g} s")
        time.sleep(0.02)


def rss_kb(pid: int, field: str = "VmRSS") -> int:
    """Resident set size of a process [kB] (VmRSS of /proc/<pid>/status; ``field`` RssAnon:
    its anonymous part, the heap and stacks, without the file pages the kernel may drop)."""
    with open(f"/proc/{pid}/status") as status:
        for line in status:
            if line.startswith(f"{field}:"):
                return int(line.split()[1])
    raise RuntimeError(f"no {field} for process {pid}")
