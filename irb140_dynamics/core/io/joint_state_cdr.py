"""sensor_msgs/JointState as the bytes DDS carries (CDR): a file format of the wire, read and
written here without ROS (``ros.messages.joint_messages`` hands anything else to rclpy).

rclpy converts every message taken into Python field by field, and every one published back;
id_node reads its joint states from the bytes with ``struct`` (strings as rclpy reads them)
and publishes its torques as bytes written once, only the stamp and efforts rewritten
(bench/bench_nodes.py measures the saving). The layout is XCDR1, as rmw_fastrtps and
rmw_cyclonedds send it: a 4-byte encapsulation header, then the fields in order, each
primitive aligned to its size from the end of the header; a string is a uint32 length (NUL
included) and its bytes, a sequence a uint32 count and its elements. Anything but
little-endian plain CDR (encapsulation 0x0001) is not read here (``read_plain`` refuses it).
"""

from __future__ import annotations

import struct
from typing import NamedTuple

import numpy as np

from irb140_dynamics.core.model.joint_order import BadMessage

PLAIN_CDR_LE = b"\x00\x01"  # the encapsulation kind this module reads itself
HEADER = 4  # bytes of the encapsulation header; alignment counts from its end
_UINT32 = struct.Struct("<I")
_STAMP = struct.Struct("<iI")
_FRAME_ID = HEADER + _STAMP.size  # where the frame_id starts
_names_seen: tuple[bytes, str, tuple] | None = None  # the bytes of the last frame_id and names read, and them
_tail_seen: tuple | None = None  # (where, length, Struct, counts, indices) of the last message's sequences


class Time(NamedTuple):
    sec: int
    nanosec: int


class Header(NamedTuple):
    stamp: Time
    frame_id: str


class JointStateView(NamedTuple):
    """The fields of a JointState read from its bytes, as a JointState has them."""

    header: Header
    name: tuple
    position: tuple
    velocity: tuple
    effort: tuple


def read_plain(raw: bytes) -> JointStateView:
    """The JointState ``raw`` serializes as little-endian plain CDR; BadMessage ``malformed``
    if it does not (``is_plain(raw)`` tells whether it claims to)."""
    try:
        return _read_plain_le(raw)
    except (struct.error, ValueError) as error:
        raise BadMessage("malformed", f"undecodable joint state: {error}") from None


def is_plain(raw: bytes) -> bool:
    return raw[:2] == PLAIN_CDR_LE


def _read_plain_le(raw: bytes) -> JointStateView:
    global _names_seen
    end = len(raw)
    sec, nanosec = _STAMP.unpack_from(raw, HEADER)
    seen = _names_seen
    if seen is not None and raw.startswith(seen[0], _FRAME_ID):  # a stream repeats them: decoded once
        block, frame_id, names = seen
        at = _FRAME_ID + len(block)
    else:
        frame_id, at = _string(raw, _FRAME_ID)
        at = _aligned(at, 4) + 4
        (count,) = _UINT32.unpack_from(raw, at - 4)
        if count * 5 > end - at:  # a name takes 5 bytes at least (length, NUL)
            raise ValueError(f"a sequence of {count} does not fit in {end} bytes")
        listed = []
        for _ in range(count):
            name, at = _string(raw, at)
            listed.append(name)
        names = tuple(listed)
        _names_seen = (raw[_FRAME_ID:at], frame_id, names)
    tail = _tail_seen
    if tail is not None and tail[0] == at and tail[1] == end:  # the layout of the last message's sequences
        _, _, layout, (c1, c2, c3), (k2, k3) = tail
        values = layout.unpack_from(raw, at)
        if values[0] == c1 and values[k2] == c2 and values[k3] == c3:  # the counts as well: read at once
            fields = values[1 : 1 + c1], values[k2 + 1 : k2 + 1 + c2], values[k3 + 1 : k3 + 1 + c3]
            return JointStateView(Header(Time(sec, nanosec), frame_id), names, *fields)
    return JointStateView(Header(Time(sec, nanosec), frame_id), names, *_sequences(raw, at, end))


def _sequences(raw: bytes, at: int, end: int) -> list[tuple]:
    """position, velocity and effort from ``at`` on; their layout kept in _tail_seen."""
    global _tail_seen
    start, fields, form, counts, where, unpacked = at, [], "<", [], [], 0
    for _ in range(3):
        pad = -(at - HEADER) % 4
        at += pad + 4
        (count,) = _UINT32.unpack_from(raw, at - 4)
        if count * 8 > end - at:
            raise ValueError(f"a sequence of {count} does not fit in {end} bytes")
        form += f"{pad}xI"
        counts.append(count)
        where.append(unpacked)
        unpacked += 1 + count
        if count == 0:
            fields.append(())
            continue
        pad = -(at - HEADER) % 8
        at += pad
        fields.append(struct.unpack_from(f"<{count}d", raw, at))
        form += f"{pad}x{count}d"
        at += 8 * count
    _tail_seen = (start, end, struct.Struct(form), tuple(counts), tuple(where[1:]))
    return fields


def _aligned(at: int, size: int) -> int:
    return at + (-(at - HEADER) % size)


def _string(raw: bytes, at: int) -> tuple[str, int]:
    """A string as rclpy reads it: up to its first NUL, undecodable UTF-8 replaced."""
    at = _aligned(at, 4)
    (length,) = _UINT32.unpack_from(raw, at)
    start, stop = at + 4, at + 4 + length
    if stop > len(raw):
        raise ValueError(f"a string of {length} bytes does not fit in {len(raw)}")
    text = raw[start:stop]
    nul = text.find(0)
    return (text if nul < 0 else text[:nul]).decode("utf-8", "replace"), stop


class EffortMessage:
    """JointState bytes with fixed names, empty positions and velocities, and efforts: written
    once; ``serialize`` writes a stamp and the efforts into a copy."""

    def __init__(self, names):
        self.names = list(names)
        self._efforts = struct.Struct(f"<{len(self.names)}d")
        self._template = _plain_le(self.names, len(self.names))
        self._at = len(self._template) - self._efforts.size  # effort is the last field

    def serialize(self, stamp, effort) -> bytes:
        """The message with ``stamp`` (anything with sec, nanosec) and ``effort`` (one per name)."""
        buffer = bytearray(self._template)
        _STAMP.pack_into(buffer, HEADER, stamp.sec, stamp.nanosec)
        if type(effort) is np.ndarray:  # floats unpacked from a list: a fifth of the cost of NumPy's scalars
            effort = effort.tolist()
        self._efforts.pack_into(buffer, self._at, *effort)
        return bytes(buffer)


def _plain_le(names, efforts: int) -> bytes:
    """A JointState with ``names``, ``efforts`` zero efforts and nothing else (stamp 0)."""
    out = bytearray(PLAIN_CDR_LE + b"\0\0")

    def align(size: int) -> None:
        out.extend(bytes(-(len(out) - HEADER) % size))

    def count(value: int) -> None:
        align(4)
        out.extend(_UINT32.pack(value))

    def string(text: str) -> None:
        encoded = text.encode() + b"\0"
        count(len(encoded))
        out.extend(encoded)

    out.extend(bytes(_STAMP.size))
    string("")  # frame_id
    count(len(names))
    for name in names:
        string(name)
    count(0)  # position
    count(0)  # velocity
    count(efforts)
    if efforts:
        align(8)
        out.extend(bytes(8 * efforts))
    return bytes(out)
