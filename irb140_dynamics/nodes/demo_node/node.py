"""demo_node: a first look at the closed loop. Sends id_node a reference motion and prints
how well the simulated arm (sim_node) follows it under computed-torque control.

Publishes    /id_node/reference         trajectory_msgs/JointTrajectory: one period of a
                                        smooth motion of every joint, sent again each period
Subscribes   joint_states, /id_node/tracking_error (sensor_msgs/JointState); effort_commands
             (std_msgs/Float64MultiArray): the first one releases the simulated arm's
             brakes, and the reference starts then, not before
Prints       the tracking error RMS per joint [mrad] over the last second, every second,
             each figure labelled with its joint; at the end (Ctrl-C, or ``duration``
             after the first figures) a plot of reference and actual positions per joint is written to
             ``plot_file`` (PNG; a relative path is from the directory the node started in;
             the full path is printed at the start and when written)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from irb140_dynamics.core.io.stamps import nanoseconds
from irb140_dynamics.core.monitoring.tracking import TrackingLog
from irb140_dynamics.core.trajectories import Trajectory
from irb140_dynamics.core.trajectories.reference import swing
from irb140_dynamics.node_help import Usage
from irb140_dynamics.ros.messages.joint_messages import trajectory_message
from irb140_dynamics.ros.parameters.arm import declare_fixed
from irb140_dynamics.ros.parameters.overrides import NODE_OPTIONS
from irb140_dynamics.ros.parameters.spec import Spec
from irb140_dynamics.ros.runtime.spin import run

NAMES = [f"joint_{i}" for i in range(1, 7)]
POINTS_PER_SECOND = 50
NODE_PARAMETERS = [
    Spec("period", 8.0, "the reference motion's period", "s", read_only=True, minimum=1.0, maximum=3600.0),
    Spec("plot_file", "demo_tracking.png", "the plot written at the end (PNG)", read_only=True),
    Spec("duration", 0.0, "stop this long after the first tracking figures; 0 = until Ctrl-C", "s", True, 0.0, 1e6),
    Spec("model_label", "id_node's model on sim_node's arm", "which model drives which arm (printout, plot)", "", True),
]


def reference_message(period: float) -> JointTrajectory:
    """One period of the demo's motion (core.trajectories.reference.swing), POINTS_PER_SECOND
    points a second, as id_node's ~/reference."""
    t = np.arange(int(period * POINTS_PER_SECOND) + 1) / POINTS_PER_SECOND
    return trajectory_message(Trajectory.of(NAMES, t, *swing(t, period)))


def _stamp(msg) -> int:
    return nanoseconds(msg.header.stamp.sec, msg.header.stamp.nanosec)


class DemoNode(Node):
    """A reference motion out; joint states and tracking errors in; figures and a plot out."""

    def __init__(self, **kwargs):
        super().__init__("demo_node", **NODE_OPTIONS, **kwargs)
        self.period, plot_file, self.duration, self.label = declare_fixed(self, NODE_PARAMETERS)
        self.plot_file = str(Path(plot_file).expanduser().resolve())
        self.log = TrackingLog()
        self._reference_pub = self.create_publisher(JointTrajectory, "/id_node/reference", 10)
        self.create_subscription(JointState, "joint_states", self._on_joint_state, 10)
        self.create_subscription(JointState, "/id_node/tracking_error", self._on_error, 10)
        self._released = False  # an effort command has come: the arm is off its brakes
        best_effort = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)  # as sim_node takes them
        self._commands = self.create_subscription(Float64MultiArray, "effort_commands", self._on_command, best_effort)
        self._start = self.get_clock().now()
        self._headed = False  # the printout's header printed
        self._sender = self.create_timer(0.1, self._start_when_heard)
        self.create_timer(1.0, self._print)
        self.get_logger().info(
            f"ready: a {self.period:g} s reference motion of {', '.join(NAMES)} for id_node, sent every period "
            f"({self.label}); the plot goes to {self.plot_file} at the end"
        )

    def _on_command(self, msg: Float64MultiArray) -> None:
        self._released = True
        self.destroy_subscription(self._commands)

    def _start_when_heard(self) -> None:
        """Send the first reference once id_node listens and the arm is off its brakes (its
        first command: the motion starts from a held arm), then one every period."""
        if self._reference_pub.get_subscription_count() == 0 or not self._released:
            return
        self._sender.cancel()
        self._send_reference()
        self.create_timer(self.period, self._send_reference)

    def _send_reference(self) -> None:
        self._reference_pub.publish(reference_message(self.period))

    def _elapsed(self) -> float:
        return (self.get_clock().now() - self._start).nanoseconds * 1e-9

    def _on_joint_state(self, msg: JointState) -> None:
        self.log.state(_stamp(msg), msg.position)

    def _on_error(self, msg: JointState) -> None:
        self.log.error(self._elapsed(), _stamp(msg), msg.position)

    def _print(self) -> None:
        """Every second: the RMS per joint over the last second, once both ends of the loop are heard."""
        t = self._elapsed()
        rms = self.log.rms(t)
        if rms is None:
            print(f"t={t:6.1f} s  waiting for sim_node and id_node ...", flush=True)
            return
        if not np.isfinite(rms).all():
            return
        if not self._headed:
            self._headed = True
            if self.duration > 0.0:  # the demo's length counts from here: the loop's start-up is not in it
                self.create_timer(self.duration, self.context.try_shutdown)  # main() then writes the plot
            print(f"tracking error RMS over the last second, per joint [mrad] ({self.label}):", flush=True)
        figures = "  ".join(f"{name} {x:7.3f}" for name, x in zip(NAMES, rms * 1e3))
        print(f"t={t:6.1f} s  {figures}  mrad", flush=True)

    def write_plot(self) -> str | None:
        """Reference and actual positions and the tracking error per joint, as a PNG
        (``tracking_plot``); its path, or None without data (then it says so)."""
        if not self.log.history:
            missing = "joint_states from sim_node" if self.log.recent else "tracking error from id_node"
            print(f"no plot: no {missing} received yet ({self.plot_file} not written)", flush=True)
            return None
        from irb140_dynamics.tracking_plot import write_tracking_plot

        write_tracking_plot(self.plot_file, *self.log.arrays(), NAMES, self.label)
        print(f"plot written: {self.plot_file}", flush=True)
        return self.plot_file

    def destroy_node(self):
        try:
            self.write_plot()
        except Exception as error:  # a plot that fails must not hide the shutdown
            self.get_logger().error(f"no plot: {error}")
        return super().destroy_node()


def usage() -> Usage:
    """What ``demo_node --help`` prints: this module's docstring and its parameters."""
    return Usage("demo_node", __doc__, [("demo_node's own", NODE_PARAMETERS)])


def main(args=None):
    raise SystemExit(run("demo_node", DemoNode, args, usage=usage))
