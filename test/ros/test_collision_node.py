"""id_node's momentum observer in-process: external_torques, the collision flag, /diagnostics."""

import re

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus

from irb140_dynamics.core import RigidBody, gravity, irb140, rnea

from ..core.test_observer import fast_motion
from ..support import collision_harness
from ..support.collision_harness import GAIN, NAMES, THRESHOLD, collision_statuses, feed

node = collision_harness.node  # the fixture

DT = 0.001  # s: 1 kHz
Q = np.array([0.0, -0.6, 0.9, 0.0, 0.4, 0.0])
PUSH = np.array([0.0, 20.0, 0.0, 0.0, 0.0, 0.0])  # N m on joint 2: the motors give g - PUSH


def summary(status: DiagnosticStatus) -> tuple:
    return status.level, status.message


def test_no_efforts_no_external_torques(node):
    for k in range(5):
        feed(node, 1 + k * DT, np.zeros(6), np.zeros(6))
    node.spin_for(0.1)
    assert node.external == []


def test_fast_motion_without_contact_stays_quiet(node):
    model = irb140()
    residuals, peak = [], 0.0
    for k in range(300):
        t = 1 + k * DT
        q, qd, qdd = fast_motion(t)
        tau = rnea(model, q, qd, qdd)
        peak = max(peak, np.abs(tau).max())
        residuals.append(feed(node, t, q, qd, tau))
    assert np.abs(residuals).max() < 0.01 * peak
    assert [m.data for m in node.collision] == [False]
    assert node.external[-1].name == NAMES


def test_step_on_joint_2_flags_a_collision_within_10_ms(node):
    g = gravity(irb140(), Q)
    assert node.spin_until(lambda: node.collision)  # the latched flag's topic matched (discovery done)
    step, settled = 50, 50 + round(5 / GAIN / DT)  # samples: the step, 5 time constants after it
    flagged_at, residuals = None, []
    for k in range(settled + 1):
        residuals.append(feed(node, 2 + k * DT, Q, np.zeros(6), g - PUSH if k >= step else g))
        if flagged_at is None and len(node.collision) > 1 and node.collision[-1].data:
            flagged_at = k
    assert next(k for k, r in enumerate(residuals) if r[1] > THRESHOLD) == step + 7  # 7 ms after the step
    assert flagged_at is not None and step < flagged_at <= step + round(0.010 / DT)
    r = residuals[settled]  # 5 time constants after the step
    assert 0.95 * 20.0 <= r[1] <= 20.0 and np.abs(r[[0, 2, 3, 4, 5]]).max() < 0.2
    # the next /diagnostics names the joint and its torque
    ended = node.node.get_clock().now()
    assert node.spin_until(lambda: collision_statuses(node, after=ended))
    status = collision_statuses(node, after=ended)[0]
    assert status.level == DiagnosticStatus.ERROR
    match = re.fullmatch(r"collision: joint_2 (-?\d+\.\d\d) N m", status.message)
    assert match and abs(float(match[1]) - r[1]) <= 0.005, status.message
    for k in range(60):  # the push ends: the flag clears
        feed(node, 2.2 + k * DT, Q, np.zeros(6), g)
    assert node.spin_until(lambda: node.collision[-1].data is False)
    assert [m.data for m in node.collision] == [False, True, False]


def test_a_collision_between_two_reports_is_reported_once(node):
    """A collision that starts and ends between two /diagnostics messages shows in the
    next as ERROR with its peak torque, and not in the one after. The reports are made
    here, the node's 1 Hz timer stopped, so that none falls inside the collision."""
    timer = next(timer for timer in node.node.timers if timer.callback == node.node._publish_diagnostics)
    timer.cancel()
    stopped = node.node.get_clock().now()  # a report published before is not one of ours

    def report():
        seen = len(collision_statuses(node, after=stopped))
        node.node._publish_diagnostics()
        assert node.spin_until(lambda: len(collision_statuses(node, after=stopped)) > seen)
        return collision_statuses(node, after=stopped)[-1]

    g = gravity(irb140(), Q)
    assert node.spin_until(lambda: node.collision)
    for k in range(20):
        feed(node, 3 + k * DT, Q, np.zeros(6), g)
    assert summary(report()) == (DiagnosticStatus.OK, "no collision")
    residuals = [feed(node, 3.02 + k * DT, Q, np.zeros(6), g - PUSH if k < 30 else g) for k in range(70)]
    assert node.spin_until(lambda: node.collision[-1].data is False)
    assert [m.data for m in node.collision] == [False, True, False]
    peak = np.abs(residuals)[:, 1].max()
    assert peak > THRESHOLD and abs(residuals[-1][1]) < THRESHOLD
    status = report()
    assert status.level == DiagnosticStatus.ERROR
    match = re.fullmatch(r"collision since last report: joint_2 (\d+\.\d\d) N m", status.message)
    assert match and abs(float(match[1]) - peak) <= 0.005, status.message
    values = {kv.key: kv.value for kv in status.values}
    assert float(values["joint_2 peak |external torque| since last report [N m]"]) == round(peak, 3)
    assert summary(report()) == (DiagnosticStatus.OK, "no collision")


def test_unmodelled_payload_is_a_static_residual(node):
    model = irb140()
    q = np.array([0.3, -0.5, 0.7, 0.2, 0.8, 0.1])
    carrying = gravity(model.with_payload(RigidBody(2.0, (0.0, 0.0, 0.05))), q)
    for k in range(100):
        r = feed(node, 3 + k * DT, q, np.zeros(6), carrying)
    np.testing.assert_allclose(r, -(carrying - gravity(model, q)), atol=0.02)


def test_bad_efforts_reset_the_observer_and_torques_still_flow(node):
    q = np.zeros(6)
    g = gravity(irb140(), q)
    for k in range(20):
        feed(node, 1 + k * DT, q, np.zeros(6), g - 5.0)
    assert np.all(np.abs(node.external[-1].effort) > 1.0)
    external = len(node.external)
    feed(node, 1.021, q, np.zeros(6), [float("nan")] * 6, observed=False)  # torques still published
    node.spin_for(0.1)
    assert len(node.external) == external
    r = feed(node, 1.022, q, np.zeros(6), g - 5.0)
    assert np.all(r == 0.0)  # started again
    assert node.node.counts["collision.effort_not_finite"] == 1
