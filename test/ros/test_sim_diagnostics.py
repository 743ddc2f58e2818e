"""sim_node's /diagnostics counts, read off the messages: steps, late and skipped steps,
republished states and push timeouts, in lockstep and in real time, with pushes timing out."""

import time

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from irb140_dynamics.nodes.sim_node.node import SimNode

from ..support.ros_harness import running
from .test_push_in_simulation import wrench
from .test_sim_lockstep import first_step, step
from .test_sim_node import make


def counts_of(msg: DiagnosticArray) -> dict[str, int] | None:
    for status in msg.status:
        if status.name.endswith(": simulation"):
            return {v.key: int(v.value) for v in status.values}
    return None


def next_counts(sim, diagnostics) -> dict[str, int]:
    """The counts of the next /diagnostics message."""
    start = len(diagnostics)
    assert sim.spin_until(lambda: len(diagnostics) > start, timeout=5.0), "no /diagnostics"
    return counts_of(diagnostics[-1])


@pytest.fixture
def lockstep():
    overrides = make(lockstep=True, rate=100.0, lockstep_timeout=0.3, command_timeout=0.02)
    with running(SimNode, parameter_overrides=overrides) as harness:
        harness.states = harness.listen(JointState, "joint_states", 1000)
        harness.clock = harness.listen(Clock, "/clock", 1000)
        harness.commands = harness.publisher(Float64MultiArray, "effort_commands")
        harness.pushes = harness.publisher(WrenchStamped, "/sim_node/external_wrench")
        yield harness


def test_lockstep_counts_its_steps_republications_and_push_timeouts(lockstep):
    sim, diagnostics = lockstep, lockstep.listen(DiagnosticArray, "/diagnostics")
    first_step(sim)
    for _ in range(4):
        step(sim, [0.0] * 6)
    counts = next_counts(sim, diagnostics)
    assert counts["steps"] == sim.node.lockstep.steps >= 5  # no push yet: steps counted all the same
    assert counts["republished"] == sim.node.lockstep.republished
    sim.pushes.publish(wrench("flange", [0.0, 0.0, 1.0]))
    assert sim.spin_until(lambda: sim.node.counts["external_wrench.received"] == 1)
    for k in range(5):  # 50 ms of simulated time: the push (timeout 20 ms) is let go
        step(
            sim, [0.0] * 5 + [1e-6 * (k + 1)]
        )  # each unlike the last (an equal answer to a republished state is dropped)
    assert sim.spin_until(lambda: sim.node.lockstep.republished >= 1, timeout=5.0)  # idle: the state again
    counts = next_counts(sim, diagnostics)
    assert counts["external_wrench.timeouts"] == 1
    assert counts["steps"] == sim.node.lockstep.steps >= 10
    assert counts["republished"] == sim.node.lockstep.republished >= 1


@pytest.fixture
def real_time():
    with running(SimNode, parameter_overrides=make(command_timeout=0.05)) as harness:
        harness.pushes = harness.publisher(WrenchStamped, "/sim_node/external_wrench")
        yield harness


def test_real_time_counts_go_on_after_a_push_timed_out_and_late_steps_still_warn(real_time):
    sim, diagnostics = real_time, real_time.listen(DiagnosticArray, "/diagnostics")
    assert sim.spin_until(lambda: sim.node.simulation.arm is not None)
    sim.pushes.publish(wrench("flange", [0.0, 0.0, 1.0]))
    assert sim.spin_until(lambda: sim.node.counts["external_wrench.timeouts"] == 1), "the push never timed out"
    before = next_counts(sim, diagnostics)
    after = next_counts(sim, diagnostics)
    assert after["external_wrench.timeouts"] == 1
    assert after["steps"] > before["steps"] > 0  # still counting after the timeout
    assert abs(after["steps"] - sim.node.loop.schedule.steps) < 2000  # the schedule's own count (1 kHz, within 2 s)
    with sim.node.simulation.lock:  # the stepping thread waits: its steps fall behind
        time.sleep(0.2)
    assert sim.spin_until(
        lambda: any(
            s.level == DiagnosticStatus.WARN and "cannot keep real time" in s.message
            for msg in diagnostics
            for s in msg.status
        ),
    )
    counts = next_counts(sim, diagnostics)
    assert counts["skipped_steps"] == sim.node.loop.schedule.skipped > 0
    assert counts["late_steps"] <= sim.node.loop.schedule.late
