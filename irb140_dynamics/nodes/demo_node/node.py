"""demo_node: a first look at the closed loop. Sends id_node a reference motion and prints
how well the simulated arm (sim_node) follows it under computed-torque control.

Publishes    /id_node/reference         trajectory_msgs/JointTrajectory: one period of a
                                        smooth motion of every joint, sent again each period
Subscribes   joint_states, /id_node/tracking_error (sensor_msgs/JointState)
Prints       the tracking error RMS per joint [mrad] over the last second, every second,
             each figure labelled with its joint; at the end (Ctrl-C, or ``duration``
             after the first figures) a plot of reference and actual positions per joint is written to
             ``plot_file`` (PNG; a relative path is from the directory the node started in;
             the full path is printed at the start and when written)
"""

from __future__ import annotations

import math
from collections import deque
from pathlib import Path

import numpy as np
from builtin_interfaces.msg import Duration
from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from irb140_dynamics.core.io.stamps import nanoseconds, sec_nanosec
from irb140_dynamics.ros.parameters.arm import declare_fixed
from irb140_dynamics.ros.parameters.overrides import NODE_OPTIONS
from irb140_dynamics.ros.parameters.spec import Spec
from irb140_dynamics.ros.runtime.command_line import Usage
from irb140_dynamics.ros.runtime.spin import run

NAMES = [f"joint_{i}" for i in range(1, 7)]
CENTRE = [0.0, -0.6, 1.0, 0.0, 0.5, 0.0]  # rad: where the motion starts and ends (sim_node's initial_positions)
AMPLITUDE = [0.8, 0.5, 0.5, 1.0, 0.6, 1.5]  # rad
POINTS_PER_SECOND = 50
HISTORY_STEP = 0.01  # s between the samples kept for the plot
NODE_PARAMETERS = [
    Spec("period", 8.0, "the reference motion's period", "s", read_only=True, minimum=1.0, maximum=3600.0),
    Spec("plot_file", "demo_tracking.png", "the plot written at the end (PNG)", read_only=True),
    Spec(
        "duration",
        0.0,
        "stop this long after the first figures (sim_node and id_node heard); 0 = until Ctrl-C",
        "s",
        read_only=True,
        minimum=0.0,
        maximum=1e6,
    ),
    Spec(
        "model_label",
        "id_node's model on sim_node's arm",
        "which model controls which arm, for the printout and the plot",
        read_only=True,
    ),
]


def motion(t: np.ndarray, period: float):
    """q, qd, qdd of c + a (1 - cos(w t)) / 2: from rest at CENTRE and back in one period."""
    w = 2 * math.pi / period
    c, a, t = np.array(CENTRE), np.array(AMPLITUDE), np.asarray(t)[:, None]
    return c + a * (1 - np.cos(w * t)) / 2, a * w * np.sin(w * t) / 2, a * w**2 * np.cos(w * t) / 2


def reference_message(period: float) -> JointTrajectory:
    """One period of the motion, POINTS_PER_SECOND points a second, as id_node's ~/reference."""
    t = np.arange(int(period * POINTS_PER_SECOND) + 1) / POINTS_PER_SECOND
    Q, QD, QDD = motion(t, period)
    msg = JointTrajectory(joint_names=NAMES)
    for ti, q, qd, qdd in zip(t, Q, QD, QDD):
        sec, nanosec = sec_nanosec(ti)
        msg.points.append(
            JointTrajectoryPoint(
                positions=q.tolist(),
                velocities=qd.tolist(),
                accelerations=qdd.tolist(),
                time_from_start=Duration(sec=sec, nanosec=nanosec),
            )
        )
    return msg


class DemoNode(Node):
    def __init__(self, **kwargs):
        super().__init__("demo_node", **NODE_OPTIONS, **kwargs)
        self.period, plot_file, self.duration, self.label = declare_fixed(self, NODE_PARAMETERS)
        self.plot_file = str(Path(plot_file).expanduser().resolve())
        self._reference_pub = self.create_publisher(JointTrajectory, "/id_node/reference", 10)
        self._positions = {}  # stamp [ns] -> q, of the latest joint states
        self._stamps = deque(maxlen=2000)
        self._recent = deque(maxlen=5000)  # (time [s], error) of the last seconds
        self._history = []  # (time [s], q_ref, q) for the plot, one every HISTORY_STEP seconds
        self._latest = None  # q of the latest joint state
        self.create_subscription(JointState, "joint_states", self._on_joint_state, 10)
        self.create_subscription(JointState, "/id_node/tracking_error", self._on_error, 10)
        self._start = self.get_clock().now()
        self._headed = False  # the printout's header printed
        self._sender = self.create_timer(0.1, self._start_when_heard)
        self.create_timer(1.0, self._print)
        self.get_logger().info(
            f"ready: a {self.period:g} s reference motion of {', '.join(NAMES)} for id_node, sent every period "
            f"({self.label}); the plot goes to {self.plot_file} at the end"
        )

    def _start_when_heard(self) -> None:
        """Send the first reference once id_node listens, then one every period."""
        if self._reference_pub.get_subscription_count() == 0:
            return
        self._sender.cancel()
        self._send_reference()
        self.create_timer(self.period, self._send_reference)

    def _elapsed(self) -> float:
        return (self.get_clock().now() - self._start).nanoseconds * 1e-9

    def _send_reference(self) -> None:
        self._reference_pub.publish(reference_message(self.period))

    @staticmethod
    def _ns(msg) -> int:
        return nanoseconds(msg.header.stamp.sec, msg.header.stamp.nanosec)

    def _on_joint_state(self, msg: JointState) -> None:
        stamp = self._ns(msg)
        if len(self._stamps) == self._stamps.maxlen:
            self._positions.pop(self._stamps[0], None)
        self._stamps.append(stamp)
        self._positions[stamp] = self._latest = np.array(msg.position)

    def _on_error(self, msg: JointState) -> None:
        t, error = self._elapsed(), np.array(msg.position)
        self._recent.append((t, error))
        if self._history and t - self._history[-1][0] < HISTORY_STEP:
            return
        # the joint state this error was computed from, else the latest (a busy machine may
        # drop it from the queue): the plot then shifts by a sample, its error RMS stays exact
        q = self._positions.get(self._ns(msg), self._latest)
        if q is not None and len(q) == len(error):
            self._history.append((t, q + error, q))

    def _print(self) -> None:
        t = self._elapsed()
        errors = [e for s, e in self._recent if s > t - 1.0]
        if not errors or not self._history:  # the loop's figures once both its ends are heard
            print(f"t={t:6.1f} s  waiting for sim_node and id_node ...", flush=True)
            return
        rms = np.sqrt(np.mean(np.square(errors), axis=0)) * 1e3
        if not np.isfinite(rms).all():
            return
        if not self._headed:
            self._headed = True
            if self.duration > 0.0:  # the demo's length counts from here: the loop's start-up is not in it
                self.create_timer(self.duration, self._finish)
            print(f"tracking error RMS over the last second, per joint [mrad] ({self.label}):", flush=True)
        figures = "  ".join(f"{name} {x:7.3f}" for name, x in zip(NAMES, rms))
        print(f"t={t:6.1f} s  {figures}  mrad", flush=True)

    def _finish(self) -> None:
        self.context.try_shutdown()  # main() then destroys the node, which writes the plot

    def write_plot(self) -> str | None:
        """Reference and actual positions and the tracking error per joint, as a PNG
        (``tracking_plot``); its path, or None without data (then it says so)."""
        if not self._history:
            missing = "tracking error from id_node" if not self._recent else "joint_states from sim_node"
            print(f"no plot: no {missing} received yet ({self.plot_file} not written)", flush=True)
            return None
        from irb140_dynamics.tracking_plot import write_tracking_plot

        t = np.array([h[0] for h in self._history])
        reference, actual = np.array([h[1] for h in self._history]), np.array([h[2] for h in self._history])
        write_tracking_plot(self.plot_file, t, reference, actual, NAMES, self.label)
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


if __name__ == "__main__":
    main()
