"""id_node on simulated time (use_sim_time: true, the clock from /clock, as beside sim_node
in lockstep), in-process: a ~/reference is sampled on simulated time whatever the wall
clock does, held and let go on it, started at its header.stamp when it has one; a
parameter change that compiles new kernels (off the executor) is applied while simulated
time stands still."""

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock

from irb140_dynamics.core import RobotModel, gravity, irb140, rnea

from .test_tracking_node import A, B, follow, send, tracking, trajectory


@pytest.fixture
def node():
    with tracking(Parameter("use_sim_time", value=True)) as harness:
        harness.clock = harness.publisher(Clock, "/clock")
        yield harness


def set_time(harness, seconds: float) -> None:
    ns = round(seconds * 1e9)
    harness.clock.publish(Clock(clock=Time(sec=ns // 10**9, nanosec=ns % 10**9)))
    assert harness.spin_until(lambda: harness.node.get_clock().now().nanoseconds == ns), "/clock not taken"


def test_the_reference_is_sampled_on_simulated_time(node):
    zeros = np.zeros(6)
    set_time(node, 100.0)
    follow(node, trajectory([(0.0, A), (1.0, B)]))
    set_time(node, 100.25)
    expected = np.add(A, 0.25 * np.subtract(B, A)) - A
    send(node, A, tracking=True)
    np.testing.assert_allclose(node.tracking[-1].position, expected, atol=1e-12)
    node.spin_for(0.3)  # wall time passes, simulated time does not: the same sample
    send(node, A, tracking=True)
    np.testing.assert_allclose(node.tracking[-1].position, expected, atol=1e-12)
    set_time(node, 101.4)  # past the last point, within reference_timeout: B held
    ff, _ = send(node, A, tracking=True)
    np.testing.assert_allclose(ff, rnea(irb140(), B, zeros, zeros), rtol=1e-12, atol=1e-12)
    set_time(node, 101.6)  # reference_timeout after the last point: let go
    ff, _ = send(node, A)
    np.testing.assert_allclose(ff, rnea(irb140(), A, zeros, zeros), rtol=1e-12, atol=1e-12)


def test_a_stamped_reference_starts_at_its_stamp(node):
    """header.stamp: the start (as joint_trajectory_controller); until then the arm is held
    where it was measured, as without a reference."""
    set_time(node, 10.0)
    _, hold = send(node, A)  # no reference: the command holds A
    msg = trajectory([(0.0, B), (1.0, A)])
    msg.header.stamp.sec = 12
    follow(node, msg)
    set_time(node, 11.9)
    n = len(node.tracking)
    _, command = send(node, A)
    np.testing.assert_array_equal(command, hold)  # not started: still held
    assert len(node.tracking) == n
    set_time(node, 12.5)
    send(node, A, tracking=True)
    np.testing.assert_allclose(node.tracking[-1].position, 0.5 * np.subtract(B, A), atol=1e-12)  # half way back


def test_a_compiled_parameter_change_applies_while_simulated_time_stands_still(node):
    set_time(node, 5.0)
    assert node.set_parameters([Parameter("joint_2.link.mass", value=30.0)])[0].successful  # settles, or fails
    assert node.node.get_clock().now().nanoseconds == 5 * 10**9
    heavier = RobotModel.from_params({**irb140().to_params(), "joint_2.link.mass": 30.0})
    send(node, A)
    np.testing.assert_allclose(node.gravity[-1].effort, gravity(heavier, A), rtol=1e-12, atol=1e-12)
    assert not np.allclose(gravity(heavier, A), gravity(irb140(), A))
