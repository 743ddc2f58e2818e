"""sim_node in lockstep, in-process: it steps once per command and never without one, its
time (/clock and the stamps) advances by exactly 1/rate per step, the states are the
engine's own stepped with the same commands, a state without an answer is published again
after lockstep_timeout (and a second, equal answer to it is dropped), and reset_hold
counts simulated time."""

import time

import numpy as np
import pytest
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger

from irb140_dynamics.core import irb140
from irb140_dynamics.nodes.sim_node.node import SimNode
from irb140_dynamics.sim.engine import SimulatedArm
from irb140_dynamics.sim.lockstep import TICKS, LockstepClock

from ..support.ros_harness import running
from .test_sim_node import POSE, make, stamp

RATE = 100.0  # Hz: 10 ms of simulated time per step
PERIOD_NS = 10_000_000


@pytest.fixture
def lockstep(request):
    # the first state goes out as the node starts, before the probe listens: the test takes
    # it as published again after lockstep_timeout, long beside the 0.3 s it spins idle
    overrides = {"lockstep": True, "rate": RATE, "lockstep_timeout": 2.0, **getattr(request, "param", {})}
    with running(SimNode, parameter_overrides=make(**overrides)) as harness:
        harness.states = harness.listen(JointState, "joint_states", 1000)
        harness.clock = harness.listen(Clock, "/clock", 1000)
        harness.commands = harness.publisher(Float64MultiArray, "effort_commands")
        yield harness


def clock_ns(msg: Clock) -> int:
    return msg.clock.sec * 1_000_000_000 + msg.clock.nanosec


def step(sim, tau) -> JointState:
    """Send one command and take the state it gives (the next stamp), once /clock has come
    too (the probe's executor takes its subscriptions in its own order)."""
    last = stamp(sim.states[-1]) if sim.states else -1
    sim.commands.publish(Float64MultiArray(data=[float(x) for x in tau]))
    assert sim.spin_until(lambda: sim.states and stamp(sim.states[-1]) > last), "no step"
    assert sim.spin_until(lambda: clock_ns(sim.clock[-1]) >= stamp(sim.states[-1])), "no /clock"
    return sim.states[-1]


def first_step(sim) -> JointState:
    """The first command may reach sim_node before its subscription has matched ours: wait
    until our publisher sees it, then send zero torque until a step is taken (each given long
    enough that a late one is not sent twice)."""
    assert sim.spin_until(lambda: sim.commands.get_subscription_count() > 0)
    for _ in range(10):
        sim.commands.publish(Float64MultiArray(data=[0.0] * 6))
        if sim.spin_until(lambda: sim.states and stamp(sim.states[-1]) > 0, timeout=3.0):
            return sim.states[-1]
    raise AssertionError("sim_node never stepped")


def test_the_clock_counts_periods_and_republishes_only_after_idle_ticks():
    clock, command = LockstepClock(0.001), np.zeros(6)
    for _ in range(3):
        clock.step(command)
    assert clock.stamp == 3_000_000 and clock.time == 0.003
    assert [clock.tick() for _ in range(TICKS)] == [False] * (TICKS - 1) + [True] and clock.republished == 1
    assert [clock.tick() for _ in range(TICKS)] == [False] * (TICKS - 1) + [True] and clock.republished == 2
    for _ in range(TICKS - 1):
        clock.tick()
    clock.step(command)  # a command: the count starts over
    assert not any(clock.tick() for _ in range(TICKS - 1)) and clock.republished == 2
    clock.steps = 10**9  # stamps stay exact periods however long it runs
    assert clock.stamp == 10**15
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError):
            LockstepClock(bad)


def test_after_a_republication_a_second_equal_answer_is_dropped_once():
    clock, a, b = LockstepClock(0.001), np.full(6, 1.0), np.full(6, 2.0)
    clock.step(a)
    assert clock.accept(a)  # no republication: equal commands are steps like any
    clock.step(a)
    while not clock.tick():
        pass
    assert clock.accept(a)  # the answer to the state published again (or to the first)
    clock.step(a)
    assert not clock.accept(a) and clock.duplicates == 1  # its twin: dropped
    assert clock.accept(a)  # once only
    while not clock.tick():
        pass
    clock.step(a)
    assert clock.accept(b) and clock.accept(a) and clock.duplicates == 1  # a different answer: no twin came
    clock.step(a)
    while not clock.tick():
        pass
    clock.step(a)
    assert not clock.accept(a) and clock.duplicates == 2  # a held arm: the next answer is the same ...
    while not clock.tick():  # ... the loop waits a timeout ...
        pass
    clock.step(a)
    assert clock.accept(a) and clock.accept(a)  # ... and then takes it for what it is


def test_each_command_is_one_step_of_the_engine_and_one_period_of_clock(lockstep):
    sim = lockstep
    assert sim.spin_until(lambda: sim.states and sim.clock)
    assert stamp(sim.states[0]) == 0 and clock_ns(sim.clock[0]) == 0 and sim.states[0].position.tolist() == POSE
    arm = SimulatedArm(irb140(), period=1.0 / RATE)  # the engine, stepped here with the same commands
    arm.reset(POSE)
    arm.step(np.zeros(6))
    state = first_step(sim)
    assert stamp(state) == PERIOD_NS
    np.testing.assert_array_equal(state.position, arm.q)
    commands = np.random.default_rng(3).normal(0.0, 20.0, (20, 6))
    for k, tau in enumerate(commands, start=2):
        state = step(sim, tau)
        arm.step(tau)
        assert stamp(state) == k * PERIOD_NS and clock_ns(sim.clock[-1]) == k * PERIOD_NS
        np.testing.assert_array_equal(state.effort, tau)
        np.testing.assert_array_equal(state.position, arm.q)  # exactly: no step more, none less
        np.testing.assert_array_equal(state.velocity, arm.qd)
    count = len(sim.states)
    sim.spin_for(0.3)  # no command: no step (and the timeout, 2 s, is not up)
    assert len(sim.states) == count and sim.node.lockstep.steps == 21
    assert [clock_ns(msg) for msg in sim.clock] == sorted(clock_ns(msg) for msg in sim.clock)


@pytest.mark.parametrize("lockstep", [{"lockstep_timeout": 0.1}], indirect=True)
def test_without_commands_the_last_state_is_republished_and_the_arm_stays(lockstep):
    sim = lockstep
    started = time.monotonic()
    assert sim.spin_until(lambda: len(sim.states) >= 3)  # the first state, then one per 0.1 s
    # no more than one per lockstep_timeout of the time it took (wall clock: what the timer counts)
    assert len(sim.states) <= 2 + (time.monotonic() - started) / 0.1, len(sim.states)
    assert all(stamp(msg) == 0 and msg.position.tolist() == POSE for msg in sim.states)
    assert all(clock_ns(msg) == 0 for msg in sim.clock)
    assert sim.node.lockstep.steps == 0 and sim.node.lockstep.republished >= 2
    assert sim.node.simulation.arm.q.tolist() == POSE  # without torque it would fall: it never stepped
    first_step(sim)  # and it goes on at the next command
    assert stamp(sim.states[-1]) == PERIOD_NS
    republished = sim.node.lockstep.republished
    assert sim.spin_until(lambda: sim.node.lockstep.republished > republished)  # state 1 again
    tau = Float64MultiArray(data=[5.0] * 6)
    sim.commands.publish(tau)  # the answer to state 1 ...
    sim.commands.publish(tau)  # ... and to its copy: a duplicate, dropped
    assert sim.spin_until(lambda: sim.node.lockstep.duplicates == 1)
    assert sim.node.lockstep.steps == 2 and sim.node.counts["effort_commands.received"] >= 3


@pytest.mark.parametrize("lockstep", [{"reset_hold": 0.05}], indirect=True)
def test_reset_hold_counts_simulated_time(lockstep):
    sim = lockstep
    first_step(sim)
    held = [step(sim, np.full(6, 50.0)) for _ in range(4)]  # steps 2..5: simulated time 0.01..0.04 < 0.05
    assert all(msg.position.tolist() == POSE and not np.any(msg.effort) for msg in held)
    applied = step(sim, np.full(6, 50.0))
    assert applied.effort.tolist() == [50.0] * 6 and applied.position.tolist() != POSE
    client = sim.probe.create_client(Trigger, "/sim_node/reset")  # a reset: the same again, from now
    assert client.wait_for_service(timeout_sec=10.0)
    reply = sim.call(lambda: client.call_async(Trigger.Request()))
    now = stamp(applied)
    assert reply.success and reply.message.endswith(
        f"held until {(now + 5 * PERIOD_NS) * 1e-9:.9f} s of simulated time"
    )
    held = [step(sim, np.full(6, 50.0)) for _ in range(5)]  # from now to now + 0.04 s: held
    assert all(msg.position.tolist() == POSE and not np.any(msg.effort) for msg in held)
    assert stamp(held[-1]) == now + 5 * PERIOD_NS  # the first step taken is from the time the reply gave
    assert step(sim, np.full(6, 50.0)).effort.tolist() == [50.0] * 6
