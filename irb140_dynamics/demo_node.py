"""demo_node: a first look. Publishes a moving joint-state stream and prints the torques.

Publishes    joint_states          sensor_msgs/JointState, every joint a slow sine inside its range
Subscribes   feedforward_torques, gravity_torques (from id_node), printed twice a second
"""

from __future__ import annotations

import math

from rclpy.node import Node
from sensor_msgs.msg import JointState

from .ros.spin import run

NAMES = [f"joint_{i}" for i in range(1, 7)]
CENTRE = [0.0, -0.6, 1.0, 0.0, 0.5, 0.0]  # rad
AMPLITUDE = [0.8, 0.5, 0.5, 1.0, 0.6, 1.5]  # rad
PERIOD = [8.0, 6.0, 5.0, 7.0, 4.0, 9.0]  # s


class DemoNode(Node):
    def __init__(self, **kwargs):
        super().__init__("demo_node", **kwargs)
        self.rate = self.declare_parameter("rate", 100.0).value  # Hz
        self._publisher = self.create_publisher(JointState, "joint_states", 10)
        self._latest = {}
        for topic in ("feedforward_torques", "gravity_torques"):
            self.create_subscription(JointState, topic, lambda msg, t=topic: self._latest.__setitem__(t, msg), 10)
        self._start = self.get_clock().now()
        self.create_timer(1.0 / self.rate, self._publish)
        self.create_timer(0.5, self._print)
        self.get_logger().info(f"ready: publishing joint_states at {self.rate} Hz")

    def _elapsed(self) -> float:
        return (self.get_clock().now() - self._start).nanoseconds * 1e-9

    def _publish(self) -> None:
        t = self._elapsed()
        w = [2 * math.pi / period for period in PERIOD]
        msg = JointState(name=NAMES)
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.position = [c + a * math.sin(wi * t) for c, a, wi in zip(CENTRE, AMPLITUDE, w)]
        msg.velocity = [a * wi * math.cos(wi * t) for a, wi in zip(AMPLITUDE, w)]
        self._publisher.publish(msg)

    def _print(self) -> None:
        feedforward, gravity = self._latest.get("feedforward_torques"), self._latest.get("gravity_torques")
        if feedforward is None or gravity is None:
            print(f"t={self._elapsed():6.1f} s  waiting for id_node ...", flush=True)
            return
        ff = " ".join(f"{x + 0.0:8.2f}" for x in feedforward.effort)
        g = " ".join(f"{x + 0.0:8.2f}" for x in gravity.effort)
        print(f"t={self._elapsed():6.1f} s  feed-forward [N m] {ff}   gravity [N m] {g}", flush=True)


def main(args=None):
    raise SystemExit(run("demo_node", DemoNode, args))


if __name__ == "__main__":
    main()
