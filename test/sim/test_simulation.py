"""sim.simulation: the arm braked until its first command (whatever reset_hold, 0 included)
and after each reset until the next; commands and pushes held, let go after
command_timeout (counted once); a model of the same joints continues, others start over.
Times are given, so every case is exact."""

from collections import Counter

import numpy as np
import pytest

from irb140_dynamics.core import RigidBody, gravity, irb140
from irb140_dynamics.core.model.joint_order import BadMessage
from irb140_dynamics.sim.engine import SimulatedArm
from irb140_dynamics.sim.simulation import Setup, Simulation, command_torques, initial_positions, problems

POSE = np.array([0.0, -0.5, 0.5, 0.0, 0.5, 0.0])  # rad: without torque the arm falls from here
MS = 1_000_000  # ns


def simulation(model=None, command_timeout=0.0, reset_hold=0.0, **noise) -> Simulation:
    sim = Simulation(Counter(), warnings.append)
    sim.use(Setup(SimulatedArm(model or irb140()), POSE, command_timeout, reset_hold, **noise), 0)
    return sim


warnings: list[str] = []


def run(sim, start_ms: int, steps: int, tau=None):
    """``steps`` steps of 1 ms from ``start_ms``; the states they leave."""
    return [sim.step((start_ms + k) * MS, tau) for k in range(steps)]


def still(states) -> bool:
    return all(np.array_equal(s.q, POSE) and not s.qd.any() and not s.effort.any() for s in states)


@pytest.mark.parametrize("reset_hold", [0.0, 0.5])
def test_braked_until_the_first_command_whatever_reset_hold(reset_hold):
    sim = simulation(reset_hold=reset_hold)
    assert still(run(sim, 0, 5000))  # 5 s without a controller: it stays
    assert sim.status(5000 * MS) == "on brakes until the first command"
    sim.command(np.zeros(6), 5000 * MS)
    states = run(sim, 5000, 300)
    assert abs(states[-1].q[1] - POSE[1]) > 1e-3  # released: zero torque, it falls


def test_reset_hold_runs_on_after_a_command_that_came_at_once():
    sim = simulation(reset_hold=0.1)
    sim.command(np.zeros(6), 0)
    assert still(run(sim, 0, 100)) and sim.status(99 * MS) == "on brakes (reset_hold)"
    assert not still(run(sim, 100, 5))


def test_after_a_reset_braked_until_the_next_command():
    sim = simulation()
    g = gravity(irb140(), POSE)
    sim.command(g, 0)
    run(sim, 0, 10)
    sim.command(np.zeros(6), 10 * MS)
    run(sim, 10, 300)  # falls
    assert sim.reset(310 * MS) and sim.counts["resets"] == 2  # the start, and this
    assert still(run(sim, 310, 1000))  # the command held before the reset is dropped
    sim.command(g, 1310 * MS)
    states = run(sim, 1310, 100)
    assert all(np.array_equal(s.effort, g) for s in states)
    np.testing.assert_allclose(states[-1].q, POSE, atol=1e-9)  # held by its gravity


def test_lockstep_steps_release_the_brakes_like_commands():
    sim = simulation(reset_hold=0.005)
    assert still(run(sim, 0, 5, np.full(6, 50.0)))  # reset_hold counts the steps' own time
    assert sim.step(5 * MS, np.full(6, 50.0)).effort.tolist() == [50.0] * 6


def test_a_stale_command_gives_zero_torque_counted_once():
    sim = simulation(command_timeout=0.05)
    tau = np.full(6, 3.0)
    sim.command(tau, 0)
    states = run(sim, 0, 100)
    assert all(np.array_equal(s.effort, tau) for s in states[:51]) and not states[51].effort.any()
    assert sim.counts["command_timeouts"] == 1 and sim.status(100 * MS) == "no command: zero torque"
    sim.command(tau, 100 * MS)
    assert np.array_equal(sim.step(100 * MS).effort, tau) and sim.status(100 * MS) == "command held"


def test_a_push_is_held_and_let_go_after_command_timeout_also_on_brakes():
    sim = simulation(command_timeout=0.02)
    wrench = np.array([0.0, 0.0, 5.0, 0.0, 0.0, 0.0])
    sim.push(wrench, "tip", 0)
    values, axes = sim.held_push(20 * MS)
    assert axes == "tip" and values.tolist() == wrench.tolist()
    run(sim, 0, 30)  # braked, no command: let go all the same
    assert sim.held_push(30 * MS) == (None, "base") and sim.counts["external_wrench.timeouts"] == 1


def test_a_model_of_the_same_joints_continues_other_joints_start_over():
    sim = simulation()
    sim.command(np.zeros(6), 0)
    run(sim, 0, 100)
    q = sim.arm.q
    heavier = Setup(SimulatedArm(irb140(payload=RigidBody(5.0))), POSE, 0.0, 0.0)
    assert not sim.use(heavier, 100 * MS)
    assert sim.arm is heavier.engine and np.array_equal(sim.arm.q, q) and sim.counts["resets"] == 1
    assert not still(run(sim, 100, 5))  # the command in force goes on


def test_noise_is_on_the_measured_state_not_the_arm():
    sim = simulation(position_noise=0.01, effort_noise=2.0)
    states = run(sim, 0, 2000)
    assert 0.008 < np.std([s.q - POSE for s in states]) < 0.012
    assert 1.6 < np.std([s.effort for s in states]) < 2.4
    assert np.array_equal(sim.arm.q, POSE)


def test_checks_of_positions_and_commands():
    model = irb140()
    assert initial_positions(model, None).tolist() == [0.0] * 6
    with pytest.raises(ValueError, match="expected 6 values"):
        initial_positions(model, [0.0] * 5)
    with pytest.raises(ValueError, match="joint_2 at -3.0 rad is outside"):
        initial_positions(model, [0.0, -3.0, 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(BadMessage, match="length_mismatch"):
        command_torques([1.0] * 5, 6)
    with pytest.raises(BadMessage, match="not_finite"):
        command_torques([np.nan] + [1.0] * 5, 6)


def test_problems_from_a_period_s_counts():
    assert problems(Counter(steps=1000, late_steps=10)) == []
    assert problems(Counter(steps=1000, late_steps=11))[0].startswith("cannot keep real time: 11 of 1000")
    assert problems(Counter(steps=1000, skipped_steps=1))
    assert problems(Counter({"effort_commands.dropped": 2, "steps.errors": 1})) == [
        "3 messages dropped or callbacks failed in the last period"
    ]
    assert problems(Counter(diverged=1)) == ["the simulation diverged and was reset"]
