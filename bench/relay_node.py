"""The baseline of the end-to-end benchmark, and a way to run a node under another executor.

    python bench/relay_node.py relay   [--executor events|single_threaded] [--ros-args ...]
    python bench/relay_node.py id_node [--executor events|single_threaded] [--ros-args ...]

``relay``: a node named ``relay`` that subscribes ``joint_states`` with exactly the QoS
id_node uses for it (``qos.reliability``, default best effort, depth ``qos.depth``,
default 10) and republishes every message unchanged on ``feedforward_torques`` (reliable,
depth ``qos.depth``, as id_node's outputs): the cost of receiving and sending a message in
rclpy without computing anything.

``id_node``: irb140_dynamics' IdNode itself, for running it under an executor other than
the one its main() uses (bench_nodes.py --executor single_threaded).

``--executor``: as irb140_dynamics.ros.runtime.spin.run takes it; ``events`` (the default) is what
every node's main() uses, ``single_threaded`` is rclpy.spin, for comparison.
``--no-event-handlers``: the node's publishers and subscriptions are created without
rclpy's default QoS event handlers (the incompatible-QoS and incompatible-type warnings),
12 waitables fewer in id_node's wait set, 6 in the relay's: what that saves per message.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from rclpy.node import Node  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

from irb140_dynamics.ros.runtime.spin import EXECUTORS, run  # noqa: E402

RELIABILITIES = {"best_effort": ReliabilityPolicy.BEST_EFFORT, "reliable": ReliabilityPolicy.RELIABLE}


class RelayNode(Node):
    """joint_states in, the same message out on feedforward_torques, nothing computed."""

    def __init__(self, **kwargs):
        super().__init__("relay", **kwargs)
        depth = self.declare_parameter("qos.depth", 10).value
        reliability = RELIABILITIES[self.declare_parameter("qos.reliability", "best_effort").value]
        self.declare_parameter("payload.mass", 0.0)  # set like id_node's in the benchmark; changes nothing here
        self._publisher = self.create_publisher(JointState, "feedforward_torques", depth)
        self.create_subscription(
            JointState, "joint_states", self._publisher.publish, QoSProfile(depth=depth, reliability=reliability)
        )
        self.get_logger().info("ready: relaying joint_states to feedforward_torques")


def make_node(kind: str):
    if kind == "relay":
        return RelayNode
    from irb140_dynamics.nodes.id_node.node import IdNode

    return IdNode


def without_event_handlers() -> None:
    """From now on, publishers and subscriptions get no default QoS event handlers."""
    from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks

    create_publisher, create_subscription = Node.create_publisher, Node.create_subscription

    def publisher(self, *args, **kwargs):
        kwargs.setdefault("event_callbacks", PublisherEventCallbacks(use_default_callbacks=False))
        return create_publisher(self, *args, **kwargs)

    def subscription(self, *args, **kwargs):
        kwargs.setdefault("event_callbacks", SubscriptionEventCallbacks(use_default_callbacks=False))
        return create_subscription(self, *args, **kwargs)

    Node.create_publisher, Node.create_subscription = publisher, subscription


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv if argv is None else argv
    ours = argv[1 : argv.index("--ros-args")] if "--ros-args" in argv else argv[1:]
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("node", choices=("relay", "id_node"))
    parser.add_argument("--executor", choices=EXECUTORS, default="events")
    parser.add_argument("--no-event-handlers", action="store_true")
    options = parser.parse_args(ours)
    if options.no_event_handlers:
        without_event_handlers()
    ros_args = argv[argv.index("--ros-args") :] if "--ros-args" in argv else []
    return run(options.node, make_node(options.node), [argv[0], *ros_args], options.executor)


if __name__ == "__main__":
    raise SystemExit(main())
