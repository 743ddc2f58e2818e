"""payload_check_node's ~/check after a model change, with the analysis of a slow model under
way (it must wait for the new model's analysis, not answer "pending"): the time from the new model's URDF to
~/check's answer, against the same with no analysis before (the baseline). Target: the
ratio at most 1.5x (the old analysis cancelled at its next check).

    .venv/bin/python bench/bench_payload_check.py [--repeat 3] [--joints 30]

In-process: the node in a fresh context each run (topic mode, check.analysis_timeout
3600 s, so that only cancelling stops the old analysis), the families and their proofs
forgotten before each run so that every run analyses the new model from scratch; runs of
the two kinds alternate.
"""

from __future__ import annotations

import argparse
import threading
import time

import rclpy
from common import Figure, Row, Target, machine_info, print_table, write_results  # first: the checkout on sys.path
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from std_msgs.msg import String
from std_srvs.srv import Trigger

from irb140_dynamics.core import irb140
from irb140_dynamics.core.payload import stop
from irb140_dynamics.core.payload.family import forget_families
from irb140_dynamics.core.urdf import export_urdf
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode
from irb140_dynamics.ros.parameters.arm import DESCRIPTION_QOS
from test.support.chains import chain_urdf

HEAD_START = 2.0  # s the slow model's analysis runs before the new model comes
TIMEOUT = 600.0  # s for any answer
CANCELLED: list[float] = []  # time.monotonic() of each analysis cancelled


def _recording(out_of_time):
    def out_of_time_recorded(self):
        try:
            return out_of_time(self)
        except stop.Cancelled:
            if self.cancel is not None:  # a build's own stop (not one nested in it)
                CANCELLED.append(time.monotonic())
            raise

    return out_of_time_recorded


stop.Stop.out_of_time = _recording(stop.Stop.out_of_time)


def answer_time(slow_urdf: str | None, stopped: list | None = None) -> float:
    """Seconds from publishing the IRB-140's URDF to ~/check's answer; before it, with
    ``slow_urdf``, that model is published and analysed for HEAD_START (and the seconds
    from the URDF to the old analysis stopped appended to ``stopped``)."""
    forget_families()
    context = Context()
    rclpy.init(context=context)
    overrides = [
        Parameter("model.source", value="robot_description"),
        Parameter("diagnostics.period", value=0.0),
        Parameter("check.analysis_timeout", value=3600.0),
    ]
    node = PayloadCheckNode(context=context, parameter_overrides=overrides)
    probe = Node("bench_probe", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(probe)

    def spin_until(done, timeout=TIMEOUT):
        deadline = time.monotonic() + timeout
        while not done() and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)
        if not done():
            raise RuntimeError("timed out")

    try:
        description = probe.create_publisher(String, "robot_description", DESCRIPTION_QOS)
        client = probe.create_client(Trigger, "/payload_check_node/check")
        spin_until(client.service_is_ready)
        if slow_urdf is not None:
            description.publish(String(data=slow_urdf))
            spin_until(lambda: node.parameters.pending_since is not None)
            head_start = time.monotonic() + HEAD_START
            spin_until(lambda: time.monotonic() > head_start)
        CANCELLED.clear()
        start = time.monotonic()
        description.publish(String(data=export_urdf(irb140())))
        future = client.call_async(Trigger.Request())
        spin_until(future.done)
        seconds = time.monotonic() - start
        if stopped is not None:
            stopped.append(CANCELLED[0] - start if len(CANCELLED) == 1 else float("nan"))
        if not future.result().message.startswith("OK: 0.000 kg fits"):
            raise RuntimeError(f"unexpected answer: {future.result().message.splitlines()[0]}")
        return seconds
    finally:
        executor.shutdown(timeout_sec=1.0)
        probe.destroy_node()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs of each kind (default 3)")
    parser.add_argument("--joints", type=int, default=30, help="the slow model's joints (default 30)")
    args = parser.parse_args()
    slow = chain_urdf(args.joints)
    answer_time(None)  # warm-up: kernels compiled, modules loaded
    baseline, superseded, stopped = [], [], []
    for _ in range(args.repeat):
        baseline.append(answer_time(None))
        superseded.append(answer_time(slow, stopped))
    threads = [t.name for t in threading.enumerate() if t.name.endswith("parameters")]
    rows = [
        Row(
            "payload_check_node, a model change (no baseline: ours vs the same without an analysis before)",
            f"URDF to ~/check answer, a {args.joints}-joint analysis under way for {HEAD_START:g} s / none",
            Figure.cost(superseded, "s"),
            Figure.cost(baseline, "s"),
            Target(1.5),
        ),
        Row(
            "payload_check_node, a model change (no baseline: ours vs the same without an analysis before)",
            f"URDF to the {args.joints}-joint analysis stopped (cancelled)",
            Figure.cost(stopped, "s"),
        ),
    ]
    print_table(rows, "bench_payload_check")
    print(f"worker threads still running: {len(threads)}")
    write_results(
        "payload_check", {"machine": machine_info(), "rows": [row.as_dict() for row in rows], "threads_left": threads}
    )


if __name__ == "__main__":
    main()
