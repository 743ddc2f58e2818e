"""The simulated arm (MuJoCo, no ROS): it integrates our physics, stops at the limits, holds by
dry friction, saturates the drives, resets when it blows up; and the real-time schedule and loop."""

import dataclasses
import os
import threading
import time

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from irb140_dynamics.core import Friction, RigidBody, forward_dynamics, gravity, irb140
from irb140_dynamics.sim.engine import SimulatedArm, SimulationError
from irb140_dynamics.sim.realtime import RealTimeLoop, StepSchedule

from ..support.common import loaded_irb140

POSE = np.array([0.3, -0.5, 0.6, 0.2, 0.8, 0.1])  # rad: away from every limit
PERIOD = 0.001  # s: the sim_node default rate, 1 kHz


def with_friction(model, viscous=0.0, coulomb=0.0):
    joints = tuple(dataclasses.replace(j, friction=Friction(viscous, coulomb)) for j in model.joints)
    return dataclasses.replace(model, joints=joints)


def unlimited(arm: SimulatedArm) -> SimulatedArm:
    arm.mj_model.jnt_limited[:] = 0
    return arm


def reference_motion(model, q0, tau, duration):
    """Our forward dynamics integrated to 1e-11 (DOP853): the motion under constant tau."""

    def f(_, x):
        return np.concatenate([x[model.n :], forward_dynamics(model, x[: model.n], x[model.n :], tau)])

    return solve_ivp(
        f,
        (0.0, duration),
        np.concatenate([q0, np.zeros(model.n)]),
        method="DOP853",
        rtol=1e-11,
        atol=1e-12,
        dense_output=True,
    ).sol


@pytest.mark.parametrize(
    "model", [loaded_irb140(), with_friction(loaded_irb140(), viscous=2.0)], ids=["frictionless", "viscous"]
)
def test_a_free_fall_follows_our_forward_dynamics(model):
    """Half a second of falling through 2.7 rad: RK4 (the default) at 1 kHz stays within
    1e-6 rad of the exact motion of our dynamics (a first-order integrator is 2e-2 rad off)."""
    arm = unlimited(SimulatedArm(model, PERIOD))
    arm.reset(POSE)
    tau = np.array([3.0, 0.0, 0.0, -1.0, 0.0, 0.5])
    exact = reference_motion(model, POSE, tau, 0.5)
    worst = 0.0
    for k in range(1, 501):
        arm.step(tau)
        worst = max(worst, np.abs(arm.q - exact(k * PERIOD)[:6]).max())
    assert np.abs(arm.q - POSE).max() > 1.0  # it did move a lot
    assert worst < 1e-6
    np.testing.assert_allclose(arm.qd, exact(0.5)[6:], atol=1e-5)
    assert arm.time == pytest.approx(0.5)


def test_substeps_integrate_at_a_finer_step():
    model = loaded_irb140()
    exact = reference_motion(model, POSE, np.zeros(6), 0.2)
    errors = []
    for substeps in (1, 4):
        arm = unlimited(SimulatedArm(model, PERIOD, substeps, "Euler"))
        arm.reset(POSE)
        for _ in range(200):
            arm.step(np.zeros(6))
        errors.append(np.abs(arm.q - exact(0.2)[:6]).max())
    assert errors[1] < errors[0] / 3  # first order: 4x finer, ~4x closer


def test_the_arm_falls_onto_its_limits_and_rests_there():
    arm = SimulatedArm(irb140(), PERIOD)
    arm.reset([0.0, -1.5, 0.0, 0.0, 0.0, 0.0])
    for _ in range(3000):
        arm.step(np.zeros(6))
    lower = irb140().joints[1].position_limits[0]
    assert arm.q[1] == pytest.approx(lower, abs=5e-3)  # a soft stop: a little give
    assert abs(arm.qd[1]) < 1e-3


def test_dry_friction_holds_below_its_level_and_slides_beyond():
    model = with_friction(loaded_irb140(), coulomb=30.0)
    extra = 20.0 * np.array([-1.0, -1.0, -1.0, 1.0, 1.0, 1.0])  # N m on top of gravity
    arm = SimulatedArm(model, PERIOD)
    arm.reset(POSE)
    for _ in range(1000):
        arm.step(gravity(model, POSE) + extra)
    assert np.abs(arm.q - POSE).max() < 2e-3  # held, creeping < 2 mrad/s (MuJoCo's soft friction)
    arm.reset(POSE)
    for _ in range(200):
        arm.step(gravity(model, POSE) + 2.0 * extra)
    assert np.abs(arm.q - POSE)[3:].min() > 0.1  # 40 N m > 30 N m: the wrist slides


def test_torques_saturate_at_the_torque_limits():
    joints = list(irb140().joints)
    joints[0] = dataclasses.replace(joints[0], torque_limit=10.0)
    arm = SimulatedArm(dataclasses.replace(irb140(), joints=tuple(joints)), PERIOD)
    arm.step([25.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    np.testing.assert_array_equal(arm.applied, [10.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    arm.step([-25.0, 0, 0, 0, 0, 0])
    assert arm.applied[0] == -10.0


def test_following_a_reference_is_stepping_it_under_pd_bit_for_bit():
    """follow (the loop of a long recording) is step at each row with the PD torque on the
    state at the step's start: the same states and applied torques, clipped alike."""
    joints = list(irb140().joints)
    joints[1] = dataclasses.replace(joints[1], torque_limit=40.0)  # joint 2 saturates at times
    model = dataclasses.replace(irb140(), joints=tuple(joints))
    t = np.arange(300) * PERIOD
    Q_ref = POSE + 0.3 * np.sin(2 * np.pi * 2.0 * t)[:, None]
    QD_ref = 0.3 * 2 * np.pi * 2.0 * np.cos(2 * np.pi * 2.0 * t)[:, None] * np.ones(6)
    feed_forward = np.array([gravity(model, q) for q in Q_ref])
    kp, kd = np.array([400.0, 400.0, 100.0, 10.0, 10.0, 5.0]), np.array([40.0, 40.0, 10.0, 1.0, 1.0, 0.5])
    stepped = SimulatedArm(model, PERIOD, substeps=2)
    stepped.reset(POSE)
    rows = []
    for k in range(len(t)):
        q, qd = stepped.q, stepped.qd
        stepped.step(feed_forward[k] + kp * (Q_ref[k] - q) + kd * (QD_ref[k] - qd))
        rows.append((q, qd, stepped.applied))
    followed = SimulatedArm(model, PERIOD, substeps=2)
    followed.reset(POSE)
    Q, QD, TAU = followed.follow(feed_forward, Q_ref, QD_ref, kp, kd)
    for got, expected in zip((Q, QD, TAU), (np.array(x) for x in zip(*rows))):
        np.testing.assert_array_equal(got, expected)
    assert np.abs(TAU[:, 1]).max() == 40.0
    np.testing.assert_array_equal(followed.q, stepped.q)
    np.testing.assert_array_equal(followed.applied, stepped.applied)
    with pytest.raises(ValueError, match="references"):
        followed.follow(feed_forward, Q_ref[:-1], QD_ref, kp, kd)
    with pytest.raises(SimulationError, match="diverged"):
        followed.follow(np.full((100, 6), 1e14), Q_ref[:100], QD_ref[:100], kp, kd)
    np.testing.assert_array_equal(followed.q, POSE)  # reset to where it was last reset


def test_a_blow_up_resets_the_arm_and_says_so():
    arm = SimulatedArm(irb140(), PERIOD)
    arm.reset(POSE)
    with pytest.raises(SimulationError, match="diverged"):
        for _ in range(100):
            arm.step([0.0, 0.0, 0.0, 0.0, 0.0, 1e14])
    np.testing.assert_array_equal(arm.q, POSE)
    np.testing.assert_array_equal(arm.qd, np.zeros(6))
    arm.step(np.zeros(6))  # and it goes on


def test_bad_arguments_are_refused_and_change_nothing():
    arm = SimulatedArm(irb140(), PERIOD)
    arm.reset(POSE)
    for bad in ([1.0] * 5, [np.nan] * 6, [np.inf] + [0.0] * 5):
        with pytest.raises(ValueError):
            arm.step(bad)
        with pytest.raises(ValueError):
            arm.reset(bad)
    np.testing.assert_array_equal(arm.q, POSE)
    assert arm.time == 0.0
    with pytest.raises(ValueError, match="substeps"):
        SimulatedArm(irb140(), PERIOD, substeps=0)
    with pytest.raises(ValueError, match="period"):
        SimulatedArm(irb140(), 0.0)


def test_a_model_change_continues_from_the_state():
    arm = SimulatedArm(irb140(), PERIOD)
    arm.reset(POSE)
    for _ in range(10):
        arm.step(np.zeros(6))
    heavier = SimulatedArm(irb140(payload=RigidBody(5.0)), PERIOD)
    heavier.take_state_of(arm)
    np.testing.assert_array_equal(heavier.q, arm.q)
    np.testing.assert_array_equal(heavier.qd, arm.qd)
    assert heavier.time == arm.time


# -- the real-time schedule ---------------------------------------------------------------


def test_schedule_on_time_runs_one_step_per_period():
    schedule = StepSchedule(0.001)
    assert [schedule.due(1.0 + k * 0.001 + 0.0002 * (-1) ** k) for k in range(100)] == [1] * 100
    assert (schedule.steps, schedule.late, schedule.skipped) == (100, 0, 0)
    assert schedule.due_time(1) == pytest.approx(1.0002)  # the first call: step 1


def test_schedule_catches_up_and_counts_late_steps():
    schedule = StepSchedule(0.001)
    schedule.due(1.0)
    assert schedule.due(1.0001) == 0  # not yet
    assert schedule.due(1.0043) == 4  # steps 2..5, due at 1.001..1.004: the first three late
    assert (schedule.steps, schedule.late) == (5, 3)
    assert schedule.due(1.0051) == 1
    assert schedule.late == 3


def test_schedule_skips_when_far_behind():
    schedule = StepSchedule(0.001, max_lag=0.05)
    schedule.due(1.0)
    assert schedule.due(1.2) == 1  # 200 steps due: one run, 199 skipped
    assert (schedule.steps, schedule.skipped, schedule.late) == (2, 199, 0)
    assert schedule.due(1.201) == 1  # and on time from there
    assert schedule.due_time(3) == pytest.approx(1.201)


def test_the_loop_steps_in_real_time_and_survives_errors():
    calls, errors = [], []

    def step(k, t):
        calls.append((k, t, time.monotonic()))
        if k == 5:
            raise RuntimeError("boom")

    loop = RealTimeLoop(0.002, step, errors.append)
    started = time.monotonic()
    loop.start()
    deadline = started + 30.0  # generous: a loaded machine may starve the loop's thread
    while len(calls) < 150 and time.monotonic() < deadline:
        time.sleep(0.01)
    loop.stop()
    elapsed = time.monotonic() - started
    count = len(calls)
    time.sleep(0.01)
    assert len(calls) == count  # stopped
    assert 150 <= count <= elapsed / 0.002 + 1  # every step due ran, none before its time
    assert [k for k, _, _ in calls] == list(range(1, count + 1))
    assert all(ran >= t - 0.001 for _, t, ran in calls)  # never early (half a period of grace)
    assert [str(e) for e in errors] == ["boom"]


def test_the_loop_runs_under_sched_fifo_when_asked_and_allowed():
    loop = RealTimeLoop(0.001, lambda k, t: None, lambda error: None)
    outcome = {}

    def starter():  # start() raises its caller's priority too: not the test's own thread
        outcome["refused"] = loop.start(priority=5)
        outcome["caller"] = os.sched_getscheduler(0)

    helper = threading.Thread(target=starter)
    helper.start()
    helper.join(5.0)
    try:
        if outcome["refused"] is None:
            assert os.sched_getscheduler(loop._thread.native_id) == os.SCHED_FIFO
            assert os.sched_getparam(loop._thread.native_id).sched_priority == 5
            assert outcome["caller"] == os.SCHED_FIFO
        else:  # no CAP_SYS_NICE here: a reason, and ordinary scheduling
            assert os.sched_getscheduler(loop._thread.native_id) == os.SCHED_OTHER
    finally:
        loop.stop()


@pytest.mark.parametrize("frame", ["base", "tip"])
def test_a_flange_wrench_is_balanced_by_the_jacobian_transpose(frame):
    """Drives giving g(q) - J(q)^T F hold the arm still under a wrench F on the flange (our
    J, MuJoCo's mapping of xfrc_applied): the torque about the flange origin was moved to
    the body's centre of mass right. Without the wrench the same torques move it."""
    from irb140_dynamics.core.monitoring.wrench import flange_jacobian_in

    model = loaded_irb140()
    F = np.array([15.0, -20.0, 10.0, 2.0, -3.0, 1.5])  # N, N m about the flange origin
    tau = gravity(model, POSE) - flange_jacobian_in(model, POSE, frame).T @ F
    arm = SimulatedArm(model)
    arm.reset(POSE)
    for _ in range(100):
        arm.step(tau, F, frame)
    assert np.abs(arm.q - POSE).max() < 1e-9 and np.abs(arm.qd).max() < 1e-7
    arm.reset(POSE)
    for _ in range(100):
        arm.step(tau)
    assert np.abs(arm.q - POSE).max() > 1e-3


def test_a_bad_wrench_is_refused():
    arm = SimulatedArm(irb140())
    arm.reset(POSE)
    for wrench, frame in (([np.nan] * 6, "base"), ([1.0] * 5, "base"), ([1.0] * 6, "world")):
        with pytest.raises(ValueError, match="wrench"):
            arm.step(np.zeros(6), wrench, frame)
    assert (arm.q == POSE).all()
