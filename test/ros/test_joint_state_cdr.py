"""id_node's own JointState (de)serialization against rclpy's, message for message, and the
one reading of a joint state into a sample."""

import math
import random
import struct

import pytest
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState

from irb140_dynamics.core.io.joint_state_cdr import EffortMessage
from irb140_dynamics.core.model.joint_order import BadMessage, JointOrder, NotForThisModel
from irb140_dynamics.ros.messages.joint_messages import read_joint_sample, read_joint_state_cdr

CHARACTERS = "abz_09é€😀"  # names of 1- to 4-byte UTF-8 characters shift every alignment


def random_joint_state(rng: random.Random, names=None) -> JointState:
    def text():
        return "".join(rng.choice(CHARACTERS) for _ in range(rng.randint(0, 9)))

    def values():
        return [
            rng.choice([rng.uniform(-1e3, 1e3), math.nan, math.inf, -0.0, 5e-324]) for _ in range(rng.randint(0, 7))
        ]

    msg = JointState(
        name=names if names is not None else [text() for _ in range(rng.randint(0, 7))],
        position=values(),
        velocity=values(),
        effort=values(),
    )
    msg.header.frame_id = text()
    msg.header.stamp.sec, msg.header.stamp.nanosec = rng.randint(-(2**31), 2**31 - 1), rng.randint(0, 2**32 - 1)
    return msg


def same_values(ours, theirs) -> bool:
    """Bit for bit (NaN == NaN, -0.0 != 0.0)."""
    return len(ours) == len(theirs) and all(struct.pack("<d", a) == struct.pack("<d", b) for a, b in zip(ours, theirs))


def assert_read_as_rclpy(raw: bytes) -> None:
    ours, theirs = read_joint_state_cdr(raw), deserialize_message(raw, JointState)
    assert (ours.header.stamp.sec, ours.header.stamp.nanosec) == (theirs.header.stamp.sec, theirs.header.stamp.nanosec)
    assert ours.header.frame_id == theirs.header.frame_id
    assert list(ours.name) == theirs.name
    for field in ("position", "velocity", "effort"):
        assert same_values(getattr(ours, field), getattr(theirs, field)), field


def test_reads_every_message_as_rclpy_does():
    rng = random.Random(1)
    for _ in range(2000):
        assert_read_as_rclpy(serialize_message(random_joint_state(rng)))


def test_a_stream_of_repeated_names_reads_as_rclpy_does():
    """The names read last are reused when the next message repeats their bytes: only then."""
    rng = random.Random(2)
    streams = [["joint_1", "joint_2"], ["joint_1", "joint_2", "joint_3"], ["joint_1"], [], ["joint_1", "joint_é"]]
    for _ in range(500):
        msg = random_joint_state(rng, names=rng.choice(streams))
        msg.header.frame_id = rng.choice(["", "base", "base_link"])
        assert_read_as_rclpy(serialize_message(msg))


def test_cut_or_damaged_bytes_are_refused_as_malformed():
    rng = random.Random(3)
    refused = 0
    for _ in range(200):
        raw = serialize_message(random_joint_state(rng))
        for damaged in (
            raw[: rng.randrange(len(raw))],
            raw[:8] + bytes(rng.randrange(256) for _ in range(len(raw) - 8)),
        ):
            try:
                read_joint_state_cdr(damaged)
            except BadMessage as error:
                assert error.kind == "malformed"
                refused += 1
    assert refused > 200


def little_endian(frame_id: bytes, names: list[bytes]) -> bytes:
    """A JointState's bytes with the strings given raw (length, then the bytes as they are)."""
    out = bytearray(b"\x00\x01\x00\x00" + struct.pack("<iI", 3, 4))

    def count(value):
        out.extend(bytes(-(len(out) - 4) % 4) + struct.pack("<I", value))

    def string(data):
        count(len(data))
        out.extend(data)

    string(frame_id)
    count(len(names))
    for name in names:
        string(name)
    for _ in range(3):  # position, velocity, effort: empty
        count(0)
    return bytes(out)


@pytest.mark.parametrize(
    "frame_id, names",
    [
        (b"b\x00se\x00", [b"joint_1\x00"]),  # an embedded NUL: the string ends there
        (b"base\x00", [b"\xff\xfe\x00", b"j\xc3\x00"]),  # not UTF-8: replaced, as rclpy does
        (b"", [b"", b"joint_1\x00"]),  # length 0: an empty string
        (b"base", [b"joint_1"]),  # no terminating NUL
    ],
)
def test_odd_strings_read_as_rclpy_reads_them(frame_id, names):
    assert_read_as_rclpy(little_endian(frame_id, names))


def test_big_endian_goes_to_rclpy():
    """A big-endian message (encapsulation 0x0000), written here by hand: read by rclpy's reader."""
    body = struct.pack(">iI", 7, 9) + struct.pack(">I", 1) + b"\0" + b"\0" * 3  # stamp, frame_id "", pad
    body += struct.pack(">I", 1) + struct.pack(">I", 2) + b"a\0" + b"\0" * 2  # name ["a"], pad to 4
    body += struct.pack(">I", 1) + struct.pack(">d", 1.5)  # position [1.5] (at 32: 8-aligned)
    body += struct.pack(">I", 0) + struct.pack(">I", 0)  # velocity, effort: empty
    msg = read_joint_state_cdr(b"\x00\x00\x00\x00" + body)
    assert isinstance(msg, JointState)
    assert (msg.header.stamp.sec, msg.name, list(msg.position)) == (7, ["a"], [1.5])


@pytest.mark.parametrize("count", [0, 1, 2, 6, 7])
def test_effort_message_is_rclpy_serialization(count):
    rng = random.Random(count)
    for _ in range(50):
        msg = random_joint_state(rng)
        names = msg.name[:count] + [f"j{i}" for i in range(count - len(msg.name[:count]))]
        expected = JointState(name=names, effort=[rng.uniform(-1e3, 1e3) for _ in names])
        expected.header.stamp = msg.header.stamp
        raw = EffortMessage(names).serialize(expected.header.stamp, expected.effort)
        back = deserialize_message(raw, JointState)
        assert back.name == names and same_values(back.effort, expected.effort)
        assert back.header.frame_id == "" and len(back.position) == len(back.velocity) == 0
        assert len(raw) <= len(serialize_message(expected))  # rclpy's may have bytes after the message
        assert (back.header.stamp.sec, back.header.stamp.nanosec) == (
            expected.header.stamp.sec,
            expected.header.stamp.nanosec,
        )


def test_a_joint_sample_is_the_same_from_the_bytes_or_the_message():
    """read_joint_sample: one value of stamp, time, q, qd and effort in the model's order,
    whatever form the joint state comes in; the clock read only for an unstamped one."""
    order = JointOrder(["a", "b", "c"])
    msg = JointState(name=["c", "x", "a", "b"], position=[3.0, 9.0, 1.0, 2.0], effort=[30.0, 0.0, 10.0, 20.0])
    msg.header.stamp.sec, msg.header.stamp.nanosec = 4, 500_000_000
    for form in (msg, serialize_message(msg)):
        sample = read_joint_sample(form, order, never)
        assert (sample.stamp.sec, sample.stamp.nanosec, sample.t) == (4, 500_000_000, 4.5)
        assert sample.q.tolist() == [1.0, 2.0, 3.0] and sample.qd.tolist() == [0.0, 0.0, 0.0]
        assert sample.effort == [10.0, 20.0, 30.0] and sample.bad_effort is None
    msg.header.stamp.sec, msg.header.stamp.nanosec = 0, 0
    msg.effort = [math.nan, 0.0, 1.0, 2.0]
    sample = read_joint_sample(serialize_message(msg), order, lambda: 7.25)
    assert sample.t == 7.25 and sample.effort is None and sample.bad_effort.kind == "effort_not_finite"
    msg.effort = [1.0]
    with pytest.raises(BadMessage, match="length_mismatch"):
        read_joint_sample(msg, order, never)
    with pytest.raises(NotForThisModel):
        read_joint_sample(JointState(name=["x"], position=[0.0]), order, never)


def never():
    raise AssertionError("a stamped joint state's time is its stamp")
