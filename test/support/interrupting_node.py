"""A node that presses Ctrl-C on itself inside a subscription callback, with more messages
waiting: main()'s spin must end cleanly (test_startup). Run as `python -m test.support.interrupting_node`."""

import os
import signal
import sys

from rclpy.node import Node
from sensor_msgs.msg import JointState

from irb140_dynamics.ros.runtime.spin import run

BURST = 20  # messages published per timer tick, to its own subscription
PRESS_AT = 30  # the message whose callback sends SIGINT


class InterruptingNode(Node):
    def __init__(self):
        super().__init__("interrupting_node")
        self.count = 0
        self.publisher = self.create_publisher(JointState, "~/burst", BURST * 5)
        self.create_subscription(JointState, "~/burst", self.on_message, BURST * 5)
        self.create_timer(0.05, self.burst)

    def burst(self) -> None:
        for _ in range(BURST):
            self.publisher.publish(JointState(name=["a"], position=[0.0]))

    def on_message(self, msg: JointState) -> None:
        self.count += 1
        if self.count == PRESS_AT:
            os.kill(os.getpid(), signal.SIGINT)
            self.pressed = True  # Python after the signal: where KeyboardInterrupt used to strike


def main() -> int:
    nodes = []
    code = run("interrupting_node", lambda: nodes.append(InterruptingNode()) or nodes[-1], sys.argv)
    print(f"exit after {nodes[-1].count} messages", flush=True)
    return code


if __name__ == "__main__":
    sys.exit(main())
