"""`ros2 param set|get` and `ros2 service call ... std_srvs/srv/Trigger` through rclpy, for
the doc-test harness (doc_blocks.py: the environment has no ros2cli). Printed as ros2cli
prints them; exit 1 when the node refuses or is not found."""

from __future__ import annotations

import sys

import rclpy
import yaml
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from std_srvs.srv import Trigger

TIMEOUT = 30.0  # s: the node's services discovered and answering, on a loaded machine


def _wait(node: Node, future) -> object:
    rclpy.spin_until_future_complete(node, future, timeout_sec=TIMEOUT)
    if not future.done():
        raise TimeoutError("no answer")
    return future.result()


def main(args: list[str]) -> int:
    rclpy.init()
    node = Node("doc_test_ros2")
    try:
        if args[0] == "param":
            target = args[2]
            client = AsyncParameterClient(node, target)
            if not client.wait_for_services(timeout_sec=TIMEOUT):
                print(f"Node not found: {target}")
                return 1
            if args[1] == "get":
                values = _wait(node, client.get_parameters([args[3]])).values
                print(f"Parameter value is: {values[0]}")
                return 0
            value = yaml.safe_load(args[4])
            result = _wait(node, client.set_parameters([Parameter(args[3], value=value)])).results[0]
            print("Set parameter successful" if result.successful else f"Setting parameter failed: {result.reason}")
            return 0 if result.successful else 1
        service, kind = args[2], args[3]
        if kind not in ("std_srvs/srv/Trigger", "std_srvs/Trigger"):
            print(f"ros2 service call: only std_srvs/srv/Trigger here, not {kind}")
            return 127
        client = node.create_client(Trigger, service)
        if not client.wait_for_service(timeout_sec=TIMEOUT):
            print(f"service {service} not available")
            return 1
        response = _wait(node, client.call_async(Trigger.Request()))
        print(f"response:\n{response}")
        return 0
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
