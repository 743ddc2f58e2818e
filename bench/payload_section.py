"""The payload check section of bench_nodes.py: check_payload cold and warm, its two halves,
and the round trip of a ~/check service call on a running payload_check_node."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import time

from common import REPO, Figure, NotMeasured, Row, seconds_per_call  # first: puts the checkout on sys.path
from node_processes import STARTUP_TIMEOUT, NodeProcess, wait_for

COLD_PROCESSES = 3  # fresh processes for the cold check_payload call
SERVICE_CALLS = 20  # ~/check calls after the first
SETTLE = 1.0  # s after ~/check appears before the first call: DDS discovery done
STRETCHED = [0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0]  # rad: the arm horizontal

COLD_SNIPPET = """
import math, time
from irb140_dynamics.core import RigidBody, check_payload, irb140
q = [0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0]
start = time.perf_counter()
check_payload(irb140(), RigidBody({payload}), q=q)
print(time.perf_counter() - start)
"""
OFF_AXIS = "3.0, (0.05, 0.0, 0.1)"  # a payload whose worst wrist poses form curves: the proof's budget is spent


def payload_rows(env: dict) -> tuple[list[Row], dict]:
    from irb140_dynamics.core import RigidBody, check_payload, derive_torque_limits, irb140, workspace_load

    group = "payload check (no baseline)"

    def cold(payload: str) -> list[float]:
        seconds = []
        for _ in range(COLD_PROCESSES):
            out = subprocess.run(
                [sys.executable, "-c", COLD_SNIPPET.format(payload=payload)],
                env=env,
                capture_output=True,
                text=True,
                timeout=120,
                check=True,
            )
            seconds.append(float(out.stdout.split()[-1]))
        return seconds

    model, payload = irb140(), RigidBody(6.0)
    limits = derive_torque_limits(model)
    timed = {
        "check_payload, cold: first call in a fresh process": cold("6.0"),
        f"check_payload, cold, RigidBody({OFF_AXIS})": cold(OFF_AXIS),
        "check_payload, warm": seconds_per_call(
            lambda: check_payload(model, payload, q=STRETCHED), blocks=7, block_seconds=0.2
        ),
        "  derive_torque_limits alone": seconds_per_call(
            lambda: derive_torque_limits(model), blocks=7, block_seconds=0.2
        ),
        "  workspace_load (the sweep and its proof) alone": seconds_per_call(
            lambda: workspace_load(model, payload, limits), blocks=7, block_seconds=0.2
        ),
    }
    rows = [Row(group, name, Figure.cost(samples, "ms")) for name, samples in timed.items()]
    service, raw = service_calls(env)
    rows += [Row(group, name, figure) for name, figure in service]
    return rows, {**{name.strip(): samples for name, samples in timed.items()}, **raw}


def service_calls(env: dict) -> tuple[list[tuple[str, Figure]], dict]:
    """Round trips of ~/check on a payload_check_node process (see _time_service_calls)."""
    names = (
        "~/check round trip, first call",
        f"~/check round trip, next {SERVICE_CALLS} calls",
        "~/check round trip, new participant at once",
    )
    if not (REPO / "irb140_dynamics" / "payload_check_node.py").is_file():
        reason = "payload_check_node missing"
        return [(name, NotMeasured(None, None, "ms", reason)) for name in names], {"service": reason}
    try:
        first, rest, at_discovery = _time_service_calls(env)
    except Exception as error:  # noqa: BLE001 - a node that does not work yet is a result too
        reason = str(error).splitlines()[0]
        print(f"  ~/check not measured: {error}", flush=True)
        return [(name, NotMeasured(None, None, "ms", reason)) for name in names], {"service": reason}
    figures = (Figure.cost([first], "ms"), Figure.cost(rest, "ms"), Figure.cost([at_discovery], "ms"))
    return list(zip(names, figures)), {
        "service_first_call_s": first,
        "service_next_calls_s": rest,
        "service_new_participant_first_call_s": at_discovery,
    }


def _time_service_calls(env: dict) -> tuple[float, list[float], float]:
    """On a fresh payload_check_node process: a client's first call, made once discovery has
    settled (SETTLE s after the service appeared), and its next calls; then a client in a
    new DDS participant (as `ros2 service call` has) calling the moment it sees the service,
    which includes the server's wait for its reply path to this participant to match."""
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from std_srvs.srv import Trigger

    namespace = f"/bench_nodes_{os.getpid()}_payload"
    process = NodeProcess(
        [
            sys.executable,
            "-c",
            "from irb140_dynamics.programs import payload_check_node; payload_check_node()",
            "--ros-args",
            "-r",
            f"__ns:={namespace}",
        ],
        env,
    )

    def calls(settle: float, count: int) -> list[float]:
        """A client in a participant of its own: wait for the service, settle, call."""
        context = Context()
        rclpy.init(context=context)
        node = executor = None
        try:
            node = Node("bench_nodes_client", context=context)
            executor = SingleThreadedExecutor(context=context)
            executor.add_node(node)
            client = node.create_client(Trigger, f"{namespace}/payload_check_node/check")
            wait_for(client.service_is_ready, STARTUP_TIMEOUT, process, "payload_check_node's ~/check")
            time.sleep(settle)
            times = []
            for _ in range(count):
                start = time.perf_counter()
                future = client.call_async(Trigger.Request())
                executor.spin_until_future_complete(future, timeout_sec=10.0)
                if not future.done():
                    raise process.fail("~/check: no reply within 10 s")
                if not future.result().message:
                    raise process.fail("~/check: an empty reply")
                times.append(time.perf_counter() - start)
            return times
        finally:
            if executor is not None:
                executor.shutdown(timeout_sec=1.0)
            if node is not None:
                node.destroy_node()
            rclpy.try_shutdown(context=context)

    try:
        settled = calls(SETTLE, 1 + SERVICE_CALLS)
        at_discovery = calls(0.0, 1)
        return settled[0], settled[1:], at_discovery[0]
    finally:
        process.stop()
