"""Publishers that know whether anything subscribes, at no cost per message.

``Publisher.get_subscription_count`` is an rcl call; asked for every
message of three topics, it cost more than the torques it saved. A ``ListenedPublisher``
keeps the count from DDS's matched events instead, served by the node's executor: a new
subscriber is counted once DDS has matched it and the executor has taken the event.
"""

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
