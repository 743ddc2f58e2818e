"""sensor_msgs/JointState from the bytes DDS carries, for id_node's path per message: plain
little-endian CDR read without rclpy (``core.io.joint_state_cdr``: a third of rclpy's cost
per message, bench/bench_nodes.py), anything else by rclpy's deserializer."""

from __future__ import annotations

from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState

from irb140_dynamics.core.io.joint_state_cdr import EffortMessage, JointStateView, is_plain, read_plain
from irb140_dynamics.core.model.joint_order import BadMessage

__all__ = ["EffortMessage", "JointStateView", "read_joint_state_cdr"]


def read_joint_state_cdr(raw: bytes) -> JointStateView | JointState:
    """The JointState ``raw`` serializes (BadMessage ``malformed`` if it does not)."""
    if is_plain(raw):
        return read_plain(raw)
    try:
        return deserialize_message(raw, JointState)
    except Exception as error:  # noqa: BLE001  (rclpy raises its own kinds for bad bytes)
        raise BadMessage("malformed", f"undecodable joint state: {error}") from None
