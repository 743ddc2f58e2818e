"""demo_node's plot: written from the tracking errors it received, even when a busy machine
dropped the joint states they were computed from; a line saying what is missing when there
is none; the tracking figures printed only once there is."""

import numpy as np
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState

from irb140_dynamics.nodes.demo_node.node import NAMES, DemoNode

from ..support.ros_harness import running


def joint_state(q, nanosec: int) -> JointState:
    msg = JointState(name=NAMES, position=list(q))
    msg.header.stamp.nanosec = nanosec
    return msg


def test_the_plot_uses_the_latest_joint_state_when_the_error_s_own_was_dropped(tmp_path, capsys):
    plot = tmp_path / "plot.png"
    with running(DemoNode, parameter_overrides=[Parameter("plot_file", value=str(plot))]) as harness:
        states = harness.publisher(JointState, "joint_states")
        errors = harness.publisher(JointState, "/id_node/tracking_error")
        q = np.linspace(-0.5, 0.5, 6)
        states.publish(joint_state(q, 1_000))
        assert harness.spin_until(lambda: harness.node.log.latest is not None)
        errors.publish(joint_state(np.full(6, 1e-3), 2_000))  # its joint state (stamp 2000) never came
        assert harness.spin_until(lambda: len(harness.node.log.history) == 1)
        t, reference, actual = harness.node.log.history[0]
        np.testing.assert_array_equal(actual, q)
        np.testing.assert_allclose(reference - actual, 1e-3, rtol=1e-12)
        assert harness.node.write_plot() == str(plot)
    assert plot.stat().st_size > 0
    assert f"plot written: {plot}" in capsys.readouterr().out


def test_without_tracking_errors_it_says_why_there_is_no_plot(tmp_path, capsys):
    plot = tmp_path / "plot.png"
    with running(DemoNode, parameter_overrides=[Parameter("plot_file", value=str(plot))]) as harness:
        assert harness.node.write_plot() is None
    assert not plot.exists()
    assert f"no plot: no tracking error from id_node received yet ({plot} not written)" in capsys.readouterr().out


def test_tracking_errors_without_joint_states_print_no_figures_and_say_what_is_missing(tmp_path, capsys):
    """The figures (what the demo's users, and test_run_script, wait for) come once a
    sample for the plot exists: then a Ctrl-C after them always writes the plot."""
    plot = tmp_path / "plot.png"
    with running(DemoNode, parameter_overrides=[Parameter("plot_file", value=str(plot))]) as harness:
        errors = harness.publisher(JointState, "/id_node/tracking_error")
        errors.publish(joint_state(np.full(6, 1e-3), 2_000))
        assert harness.spin_until(lambda: len(harness.node.log.recent) == 1)
        harness.node._print()
        assert harness.node.write_plot() is None
    out = capsys.readouterr().out
    assert "waiting for sim_node and id_node" in out and "mrad" not in out
    assert f"no plot: no joint_states from sim_node received yet ({plot} not written)" in out
