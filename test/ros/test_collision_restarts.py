"""id_node's momentum observer in-process: what restarts it (gaps, repeated and older
stamps), what leaves it alone (joint states without efforts), and the output's joint
order and stamp."""

import numpy as np
import pytest
from sensor_msgs.msg import JointState

from irb140_dynamics.core import gravity, irb140, rnea
from irb140_dynamics.core.monitoring.observer import MomentumObserver

from ..core.test_observer import fast_motion
from ..support import collision_harness
from ..support.collision_harness import GAIN, NAMES, THRESHOLD, feed, send, stamped

node = collision_harness.node  # the fixture

DT = 0.001  # s: 1 kHz
RESTARTS = ("collision.restart_gap", "collision.restart_repeated_stamp", "collision.restart_older_stamp")


@pytest.mark.parametrize("kind, step", [("gap", 0.102), ("repeated_stamp", 0.0), ("older_stamp", -0.005)])
def test_a_bad_time_step_restarts_the_observer_at_zero(node, kind, step):
    q, external = np.zeros(6), np.array([5.0, 15.0, 5.0, 5.0, 5.0, 5.0])  # N m: joint 2 over its threshold
    effort = gravity(irb140(), q) - external
    for k in range(40):
        r = feed(node, 1 + k * DT, q, np.zeros(6), effort)
    assert r[1] > THRESHOLD and node.collision[-1].data is True
    assert all(node.node.counts[key] == 0 for key in RESTARTS)
    t = 1 + 39 * DT + step
    assert np.all(feed(node, t, q, np.zeros(6), effort) == 0.0)
    assert {key: node.node.counts[key] for key in RESTARTS} == {key: int(key.endswith(kind)) for key in RESTARTS}
    assert node.spin_until(lambda: node.collision[-1].data is False)  # the flag follows the restarted residual
    # and it runs on from there: one step's rise of a first-order lag, K dt / (1 + K dt) of the step
    np.testing.assert_allclose(
        feed(node, t + DT, q, np.zeros(6), effort), external * GAIN * DT / (1 + GAIN * DT), rtol=1e-6
    )


def test_a_gap_within_0_1_s_does_not_restart_it(node):
    q, effort = np.zeros(6), gravity(irb140(), np.zeros(6)) - 5.0
    r = [feed(node, t, q, np.zeros(6), effort) for t in (1.0, 1.001, 1.098)]
    assert np.all(r[2] > r[1]) and sum(node.node.counts[key] for key in RESTARTS) == 0


def motion_with_a_push(model, t, start):
    """q, qd, measured efforts of fast_motion from ``start``, pushed on joint 2 from 10 ms on."""
    q, qd, qdd = fast_motion(t - start)
    push = np.array([0.0, 20.0, 0.0, 0.0, 0.0, 0.0]) if t - start >= 0.010 - 1e-9 else np.zeros(6)
    return q, qd, rnea(model, q, qd, qdd) - push


def test_joint_states_without_efforts_leave_the_observer_untouched(node):
    """The same run twice, the second with joint states without efforts in between: the
    same residuals to the last bit (the second starts from an older stamp: a restart)."""
    model = irb140()
    times = [1 + k * DT for k in range(40)]
    plain = [feed(node, t, *motion_with_a_push(model, t, 1.0)) for t in times]
    interleaved = []
    for t in times:
        interleaved.append(feed(node, t, *motion_with_a_push(model, t, 1.0)))
        q, qd, _ = motion_with_a_push(model, t + DT / 2, 1.0)
        feed(node, t + DT / 2, q, qd)  # no efforts: torques, and nothing on external_torques
    node.spin_for(0.05)
    assert len(node.external) == 2 * len(times)
    assert np.array_equal(plain, interleaved)
    assert abs(plain[-1][1]) > THRESHOLD  # the push shows: a run worth comparing
    assert node.node.counts["collision.restart_older_stamp"] == 1


def test_external_torques_carry_the_input_stamp_in_model_joint_order(node):
    model = irb140()
    observer = MomentumObserver(model, GAIN)
    order = [3, 0, 5, 1, 4, 2]  # the joint states' joints: joint_4, joint_1, ...
    external = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    for k in range(30):
        msg = stamped(JointState(name=[NAMES[j] for j in order]), 1_700_000_000 + 0.123456789 + k * DT)
        t = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec  # as the node reads it
        q, qd, qdd = fast_motion(t - 1_700_000_000)
        effort = rnea(model, q, qd, qdd) - external
        msg.position, msg.velocity, msg.effort = (x[order].tolist() for x in (q, qd, effort))
        r = send(node, msg)
        out = node.external[-1]
        assert out.name == NAMES
        assert (out.header.stamp.sec, out.header.stamp.nanosec) == (msg.header.stamp.sec, msg.header.stamp.nanosec)
        np.testing.assert_allclose(r, observer.update(t, q, qd, effort), rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(r, external, rtol=0.1)  # each joint's own torque, in the model's order
