"""A MarkerArray of the markers id_node draws as the bytes a publisher sends (CDR,
little-endian, as ``rclpy.serialization.serialize_message`` gives), made in Python with
each marker's constant parts (frame, namespace, id, type, action, lifetime, the empty
texture, mesh and colour lists) encoded once.

rclpy converts a message field by field before serialising it, every Marker whatever
changed; ``packed`` writes only what a marker's update changes (stamp, pose, scale, colour,
points, text) between chunks kept per marker. Markers with per-vertex colours, textures,
uv coordinates or meshes are not among id_node's: ``packed`` refuses them (ValueError).
"""

from __future__ import annotations

from struct import Struct

from visualization_msgs.msg import Marker, MarkerArray

ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little-endian
_COUNT, _STAMP, _NUMBERS, _POINT = Struct("<I"), Struct("<iI"), Struct("<10d4f"), Struct("<3d")


def packed(array: MarkerArray) -> bytes:
    """``array``'s serialised bytes (see the module), publishable as they are."""
    out = bytearray(ENCAPSULATION)
    out += _COUNT.pack(len(array.markers))
    for marker in array.markers:
        _write(out, marker, _chunks_of(marker))
    return bytes(out)


def _write(out: bytearray, m: Marker, chunks: tuple[bytes, bytes, bytes, bytes]) -> None:
    after_stamp, after_colour, before_text, after_text = chunks
    out += b"\0" * (-len(out) % 4)  # 4-aligned from the data's start (4 bytes in) as from here
    stamp = m.header.stamp
    out += _STAMP.pack(stamp.sec, stamp.nanosec)
    out += after_stamp
    out += b"\0" * (-(len(out) - 4) % 8)  # the pose: 8-aligned from the data's start
    p, o, s, c = m.pose.position, m.pose.orientation, m.scale, m.color
    out += _NUMBERS.pack(p.x, p.y, p.z, o.x, o.y, o.z, o.w, s.x, s.y, s.z, c.r, c.g, c.b, c.a)
    out += after_colour
    points = m.points
    out += b"\0" * (-len(out) % 4)
    out += _COUNT.pack(len(points))
    if points:
        out += b"\0" * (-(len(out) - 4) % 8)
        for point in points:
            out += _POINT.pack(point.x, point.y, point.z)
    out += b"\0" * (-len(out) % 4)
    out += before_text
    text = m.text.encode()
    out += _COUNT.pack(len(text) + 1)
    out += text
    out += b"\0" + b"\0" * (-(len(out) + 1) % 4)
    out += after_text


def _chunks_of(m: Marker) -> tuple[bytes, bytes, bytes, bytes]:
    """The marker's constant bytes, each chunk starting 4-aligned (so its own padding is
    the same wherever it goes); refused for fields id_node never fills."""
    if m.colors or m.uv_coordinates or m.texture_resource or m.texture.data or m.texture.format:
        raise ValueError(f"marker {m.ns} {m.id}: colours, textures or uv coordinates are not packed")
    if m.mesh_resource or m.mesh_file.filename or m.mesh_file.data or m.texture.header.frame_id:
        raise ValueError(f"marker {m.ns} {m.id}: meshes are not packed")
    key = (m.header.frame_id, m.ns, m.id, m.type, m.action, m.lifetime.sec, m.lifetime.nanosec, m.frame_locked)
    key += (m.texture.header.stamp.sec, m.texture.header.stamp.nanosec, m.mesh_use_embedded_materials)
    try:
        return _CHUNKS[key]
    except KeyError:
        pass
    after_stamp = _string(m.header.frame_id) + _string(m.ns)
    after_stamp += Struct("<iii").pack(m.id, m.type, m.action)
    after_colour = _STAMP.pack(m.lifetime.sec, m.lifetime.nanosec) + bytes([m.frame_locked])
    texture_stamp = _STAMP.pack(m.texture.header.stamp.sec, m.texture.header.stamp.nanosec)
    empty, none = _string(""), _COUNT.pack(0)
    before_text = none + empty + texture_stamp + empty + empty + none + none  # colors .. uv_coordinates
    after_text = empty + empty + none + bytes([m.mesh_use_embedded_materials])  # mesh_resource .. the flag
    _CHUNKS[key] = chunks = (after_stamp, after_colour, before_text, after_text)
    return chunks


_CHUNKS: dict[tuple, tuple[bytes, bytes, bytes, bytes]] = {}


def _string(text: str) -> bytes:
    """A CDR string (length with its terminating zero, the bytes, zero) padded to 4 bytes."""
    data = text.encode() + b"\0"
    return _COUNT.pack(len(data)) + data + b"\0" * (-len(data) % 4)
