"""sim_node in-process with real rclpy and DDS: commands in, states out, hold and timeout,
reset, noise, bad commands, parameters."""

import time
from contextlib import contextmanager

import numpy as np
import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.context import Context
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger

from irb140_dynamics.core import RigidBody, gravity, irb140
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.sim_node import node as sim_node
from irb140_dynamics.nodes.sim_node.node import SimNode

from ..support.ros_harness import TIMEOUT, Harness, running

NAMES = [f"joint_{i}" for i in range(1, 7)]
POSE = [0.0, -0.5, 0.5, 0.0, 0.5, 0.0]  # rad: without torques the arm falls from here
COMMAND = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]  # N m


def make(**parameters):
    overrides = {"initial_positions": POSE, "command_timeout": 0.0, **parameters}
    return [Parameter(name, value=value) for name, value in overrides.items()]


@pytest.fixture
def sim(request):
    with running(SimNode, parameter_overrides=make(**getattr(request, "param", {}))) as harness:
        harness.states = harness.listen(JointState, "joint_states", 1000)
        harness.commands = harness.publisher(Float64MultiArray, "effort_commands")
        yield harness


@contextmanager
def sim_with_controller(**parameters):
    """(harness, add_controller): a SimNode (``make(**parameters)``) in a context of its own,
    spun by a Harness; ``add_controller(overrides)`` adds an id_node beside it. Both are
    destroyed after, whatever happens."""
    context = Context()
    rclpy.init(context=context)
    harness, controllers = None, []

    def add_controller(overrides) -> IdNode:
        controllers.append(IdNode(context=context, parameter_overrides=overrides))
        harness.executor.add_node(controllers[-1])
        return controllers[-1]

    try:
        harness = Harness(context, SimNode(context=context, parameter_overrides=make(**parameters)))
        yield harness, add_controller
    finally:
        for controller in controllers:
            harness.executor.remove_node(controller)
            controller.destroy_node()
        if harness is not None:
            harness.close()
        rclpy.try_shutdown(context=context)


def command(sim, tau):
    sim.commands.publish(Float64MultiArray(data=[float(x) for x in tau]))


def states_after(sim, count: int):
    """The next ``count`` joint states."""
    start = len(sim.states)
    assert sim.spin_until(lambda: len(sim.states) >= start + count), "joint_states stopped"
    return sim.states[start : start + count]


def wait_for_effort(sim, tau, timeout=TIMEOUT):
    assert sim.spin_until(lambda: sim.states and np.array_equal(sim.states[-1].effort, tau), timeout), (
        f"effort never became {list(tau)}"
    )


def stamp(msg) -> int:
    """ns"""
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def states_after_reset(sim, count: int, tau=None):
    """Reset the arm (on brakes until a command comes), command ``tau`` (None: zero torque)
    and the first ``count`` joint states stepped after the reset, from the first that
    carries ``tau`` as its effort (while braked the effort is zero)."""
    first = len(sim.states)
    sim.node.reset()
    reset_at = sim.node.reset_stamp
    tau = np.zeros(6) if tau is None else np.asarray(tau, dtype=float)
    command(sim, tau)

    def under_tau():
        after = [msg for msg in sim.states[first:] if stamp(msg) > reset_at]
        start = next((i for i, msg in enumerate(after) if np.array_equal(msg.effort, tau)), len(after))
        return after[start:]

    assert sim.spin_until(lambda: len(under_tau()) >= count), "joint_states stopped"
    return under_tau()[:count]


def states_stepped_after(sim, reset_at: int, count: int):
    """Once the last ``count`` states received were stepped after ``reset_at`` (a reset's
    ``reset_stamp``), every state stamped after it, in order: by stamp, as the probe may lag."""
    assert sim.spin_until(lambda: sum(stamp(msg) > reset_at for msg in sim.states[-count:]) == count)
    return [msg for msg in sim.states if stamp(msg) > reset_at]


def test_states_are_named_stamped_every_period_and_the_arm_falls_without_torque(sim):
    states = states_after_reset(sim, 300)  # from the pose: the arm rests on its joint limit 0.5 s later
    assert all(msg.name == NAMES for msg in states)
    steps = np.diff([stamp(msg) for msg in states]) / 1_000_000  # ms: the probe may miss some under load
    assert steps.min() >= 1 and np.abs(steps - np.round(steps)).max() < 1e-6  # 1 kHz in stamps
    assert all(not np.any(msg.effort) for msg in states)
    position = np.array([msg.position for msg in states])
    assert abs(position[-1, 1] - position[0, 1]) > 1e-3  # joint 2 falls


def test_a_gravity_command_is_applied_and_held(sim):
    g = gravity(irb140(), POSE)
    states = states_after_reset(sim, 500, g)
    position = np.array([msg.position for msg in states])
    assert np.abs(position - POSE).max() < 1e-6  # held exactly: the engine's gravity is ours
    assert all(np.array_equal(msg.effort, g) for msg in states)  # one command, held


@pytest.mark.parametrize("sim", [{"command_timeout": 0.2}], indirect=True)
def test_a_command_older_than_the_timeout_gives_zero_torque(sim):
    sent = time.monotonic()  # the node ages commands on this clock (stamps are the steps' due times)
    command(sim, COMMAND)
    wait_for_effort(sim, COMMAND)
    applied = [msg for msg in sim.states if np.array_equal(msg.effort, COMMAND)]
    wait_for_effort(sim, np.zeros(6))
    assert time.monotonic() - sent >= 0.2  # not dropped before its time
    assert 0 < stamp(sim.states[-1]) - stamp(applied[0]) < 2e9  # and dropped (the bound: a stall)
    assert sim.node.counts["command_timeouts"] == 1
    command(sim, COMMAND)  # a fresh command applies again
    wait_for_effort(sim, COMMAND)


def test_bad_commands_are_dropped_counted_and_never_applied(sim):
    diagnostics = sim.listen(DiagnosticArray, "/diagnostics")
    command(sim, COMMAND)
    wait_for_effort(sim, COMMAND)
    for bad in (COMMAND[:5], COMMAND + [7.0], [np.nan] + COMMAND[1:], COMMAND[:5] + [np.inf]):
        command(sim, bad)
    assert sim.spin_until(lambda: sim.node.counts["effort_commands.dropped"] == 4)
    assert all(np.array_equal(msg.effort, COMMAND) for msg in states_after(sim, 100))
    counts = sim.node.counts
    assert counts["effort_commands.dropped_length_mismatch"] == 2 and counts["effort_commands.dropped_not_finite"] == 2
    assert sim.spin_until(
        lambda: any(
            s.level == DiagnosticStatus.WARN and "dropped" in s.message for msg in diagnostics for s in msg.status
        ),
    )


def test_no_exception_leaves_a_callback(sim, monkeypatch):
    """A defect of ours in a callback (here: made to raise) is counted per topic and warned
    about; the node goes on, and a service answers that it failed."""
    diagnostics = sim.listen(DiagnosticArray, "/diagnostics")

    def broken(msg, n):
        raise RuntimeError("a defect")

    monkeypatch.setattr(sim_node, "command_torques", broken)
    command(sim, COMMAND)
    assert sim.spin_until(lambda: sim.node.counts["effort_commands.errors"] >= 1)
    monkeypatch.undo()
    command(sim, COMMAND)
    wait_for_effort(sim, COMMAND)  # commands apply again
    monkeypatch.setattr(sim.node, "reset", lambda: 1 / 0)
    client = sim.probe.create_client(Trigger, "/sim_node/reset")
    assert client.wait_for_service(timeout_sec=10.0)
    reply = sim.call(lambda: client.call_async(Trigger.Request()))
    assert not reply.success and reply.message == "reset failed: division by zero"
    assert sim.node.counts["reset.errors"] == 1
    assert sim.spin_until(
        lambda: any(
            s.level == DiagnosticStatus.WARN and "callbacks failed" in s.message
            for msg in diagnostics
            for s in msg.status
        ),
    )
    states_after(sim, 50)  # still stepping


def test_diagnostics_warn_when_real_time_is_lost(sim):
    diagnostics = sim.listen(DiagnosticArray, "/diagnostics")
    with sim.node.simulation.lock:  # the stepping thread waits: its steps fall behind
        time.sleep(0.2)
    assert sim.spin_until(
        lambda: any(
            s.level == DiagnosticStatus.WARN and "cannot keep real time" in s.message
            for msg in diagnostics
            for s in msg.status
        ),
    )
    assert sim.node.loop.schedule.skipped > 0


def test_a_blow_up_resets_the_arm_and_the_node_goes_on(sim):
    command(sim, [0.0, 0.0, 0.0, 0.0, 0.0, 1e14])
    assert sim.spin_until(lambda: sim.node.counts["diverged"] > 0)
    command(sim, np.zeros(6))
    states_after(sim, 50)
    assert np.isfinite(sim.states[-1].position).all()


def moved(msg) -> bool:
    return msg.position.tolist() != POSE or np.any(msg.velocity) or np.any(msg.effort)


def test_the_arm_is_on_brakes_until_its_first_command(sim):
    """Started before its controller, the arm holds still (reset_hold 0), then falls under zero torque."""
    assert sim.spin_until(lambda: len(sim.states) >= 500)
    assert not any(moved(msg) for msg in sim.states)
    command(sim, np.zeros(6))
    assert sim.spin_until(lambda: sim.states and abs(sim.states[-1].position[1] - POSE[1]) > 1e-3)  # released: it falls


@pytest.mark.parametrize("sim", [{"reset_hold": 0.3}], indirect=True)
def test_reset_puts_the_arm_back_on_brakes_until_a_command_and_reset_hold(sim):
    command(sim, np.zeros(6))
    assert sim.spin_until(lambda: sim.states and abs(sim.states[-1].position[1] - POSE[1]) > 1e-3)  # fallen
    client = sim.probe.create_client(Trigger, "/sim_node/reset")
    assert client.wait_for_service(timeout_sec=10.0)
    reply = sim.call(lambda: client.call_async(Trigger.Request()))
    assert reply.success and "reset" in reply.message
    after = states_stepped_after(sim, sim.node.reset_stamp, 600)  # twice reset_hold, no command since: braked
    assert len(after) >= 600 and not any(moved(msg) for msg in after)
    sim.node.reset()
    reset_at = sim.node.reset_stamp
    command(sim, np.zeros(6))  # at once: braked for reset_hold all the same
    assert sim.spin_until(lambda: sim.states[-1].position[1] < POSE[1] - 1e-3)  # released
    released = next(msg for msg in sim.states if stamp(msg) > reset_at and moved(msg))
    assert stamp(released) - reset_at >= 0.3e9


@pytest.mark.parametrize("sim", [{"reset_hold": 100.0, "noise.position": 0.01, "noise.effort": 2.0}], indirect=True)
def test_noise_on_positions_and_efforts(sim):
    states = states_after(sim, 400)
    position = np.array([msg.position for msg in states]) - POSE
    effort = np.array([msg.effort for msg in states])
    assert 0.008 < position.std() < 0.012 and abs(position.mean()) < 0.002
    assert 1.6 < effort.std() < 2.4
    assert sim.node.simulation.arm.q.tolist() == POSE  # the noise is on the messages, not the arm
    assert not np.any(np.array([msg.velocity for msg in states]))


def test_runtime_changes_apply_and_bad_ones_are_refused(sim):
    g = gravity(irb140(payload=RigidBody(5.0)), POSE)
    results = sim.set_parameters([Parameter("payload.mass", value=5.0)])
    assert [r.successful for r in results] == [True]
    assert sim.node.simulation.arm.model.payload.mass == 5.0
    position = np.array([msg.position for msg in states_after_reset(sim, 200, g)])
    assert np.abs(position - POSE).max() < 1e-6  # the new payload is simulated
    for name, value, reason in [
        ("initial_positions", [0.0] * 5, "expected 6 values"),
        ("initial_positions", [0.0, -3.0, 0.0, 0.0, 0.0, 0.0], "joint_2 at -3.0 rad is outside"),
        ("payload.mass", -1.0, "payload.mass"),
        ("rate", 10.0, "read-only"),
    ]:
        result = sim.set_parameters([Parameter(name, value=value)])[0]
        assert not result.successful and reason in result.reason, (name, result.reason)
    assert sim.node.simulation.arm.model.payload.mass == 5.0


@pytest.mark.parametrize(
    "overrides, field",
    [
        ({"initial_positions": [0.0] * 3}, "initial_positions"),
        ({"integrator": "leapfrog"}, "integrator"),
        ({"substeps": 0}, "substeps"),
        ({"thread_priority": 100}, "thread_priority"),
    ],
)
def test_a_bad_start_is_one_clear_error(overrides, field):
    with pytest.raises(ValueError, match=field), running(SimNode, parameter_overrides=make(**overrides)):
        pass
