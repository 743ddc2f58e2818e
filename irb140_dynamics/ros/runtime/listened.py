"""Publishers that know whether anything subscribes, at no cost per message: the count comes
from DDS's matched events (served by the node's executor), not from an rcl call per message
(``get_subscription_count``: it cost more than the torques it saved)."""

from __future__ import annotations

from rclpy.event_handler import PublisherEventCallbacks


class ListenedPublisher:
    """A node's publisher of ``msg_type`` on ``topic`` and its number of matched subscribers."""

    def __init__(self, node, msg_type, topic: str, qos):
        self.subscribers = 0
        self.publisher = node.create_publisher(
            msg_type, topic, qos, event_callbacks=PublisherEventCallbacks(matched=self._matched)
        )

    def _matched(self, status) -> None:
        self.subscribers = status.current_count

    def publish(self, msg) -> None:
        self.publisher.publish(msg)
