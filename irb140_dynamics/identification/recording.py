"""Recorded joint states, read in chunks: ROS 2 bags (through rosbags) and CSV files; and the
bags `record` writes (``open_bag``, ``bag_connection``), so that the format is read and
written in one place.

A recording yields ``RawChunk``s of at most ``chunk_size`` samples, so that memory stays
bounded whatever its length. A sample is one JointState message (one CSV row): its time,
and the model's joints' positions, velocities and efforts, the joints matched by name like
id_node does (any order, other joints ignored; an unnamed message positionally when its
length is the model's). What cannot be used is left out and counted in ``skipped`` by
reason; velocities or efforts a sample lacks are NaN (the caller leaves it out).

Time: the header stamp, or the bag's receive time when the stamp is zero (s, from the
first sample). CSV columns, in any order, others ignored (``docs/identification.md``):
``time`` [s], ``position_<joint>`` [rad], ``velocity_<joint>`` [rad/s] (optional),
``effort_<joint>`` [N m]; an empty cell is a missing value. Short names work too (``CSV_NAMES``):
``t``, ``q_<joint>``, ``qd_<joint>``, ``tau_<joint>``, where ``<joint>`` is the joint's name
or its number in the model (1 for the first joint), as in ``t,q_1,...,qd_1,...,tau_1,...``.
"""

from __future__ import annotations

import csv
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from itertools import islice
from pathlib import Path

import numpy as np

from irb140_dynamics.core.io.stamps import seconds
from irb140_dynamics.core.model.joint_order import BadMessage, JointOrder

JOINT_STATE = "sensor_msgs/msg/JointState"
DEFAULT_TOPIC = "/joint_states"
CHUNK_SIZE = 20_000
CSV_LINE_LIMIT = 1 << 20  # bytes: a longer CSV line is refused (a joint-state row has a few hundred)
BAG_SUFFIXES = (".mcap", ".db3")


class RecordingError(ValueError):
    """A recording that cannot be used: names the file and the problem."""

    def __init__(self, path, problem: str):
        super().__init__(f"{path}: {problem}")
        self.path, self.problem = str(path), problem


@dataclass(frozen=True, eq=False)
class RawChunk:
    first: int  # index of the first sample in the recording
    time: np.ndarray  # (N,) s
    position: np.ndarray  # (N, n) rad
    velocity: np.ndarray  # (N, n) rad/s, NaN where absent
    effort: np.ndarray  # (N, n) N m, NaN where absent

    def __len__(self) -> int:
        return len(self.time)


class Recording:
    """A recording of the model's joints: ``total`` samples expected, ``chunks()`` to read."""

    def __init__(self, path, joint_names, topic: str = DEFAULT_TOPIC, chunk_size: int = CHUNK_SIZE):
        self.path = Path(path)
        self.order = JointOrder(joint_names)
        self.n = len(self.order.joint_names)
        self.topic = topic
        self.chunk_size = chunk_size
        self.skipped: Counter = Counter()
        if not self.path.exists():
            raise RecordingError(path, "no such file or directory")
        if self.path.suffix.lower() == ".csv":
            self._source = _CsvSource(self)
        elif self.path.is_dir() or self.path.suffix.lower() in BAG_SUFFIXES:
            self._source = _BagSource(self)
        else:
            raise RecordingError(path, "not a ROS 2 bag (.mcap, .db3 or a bag directory) nor a .csv file")
        self.total = self._source.total

    def chunks(self) -> Iterator[RawChunk]:
        yield from self._source.chunks()


class _BagChunker:
    """Collects a bag's messages into RawChunks, with as little work per message as can be
    (a long bag has millions): the bytes of its arrays are appended to buffers, so that the
    message is freed at once (keeping thousands alive costs more than the copy), its stamp's
    integers and receive time to lists (nothing the garbage collector has to visit); the
    times and the joint order are worked out a chunk at a time, in NumPy."""

    def __init__(self, recording: Recording):
        self.recording = recording
        self.first = 0
        self.positions, self.velocities, self.efforts = bytearray(), bytearray(), bytearray()
        self.seconds, self.nanoseconds, self.receive_times = [], [], []
        self.index, self.length, self.bad = None, -1, None  # the joint mapping of the messages collected
        self.missing = np.zeros(0)  # the values of an absent velocity or effort: NaN, ``length`` of them
        self.parts: list[tuple] = []  # converted messages of earlier mappings, in this chunk
        self.converted = 0  # messages in parts

    def layout(self, index, length: int, bad: str | None) -> None:
        """The mapping of the messages that come next (see _BagSource._mapping)."""
        same_index = (index is None) == (self.index is None) and (index is None or np.array_equal(index, self.index))
        if not (same_index and length == self.length):
            self._convert()
            self.missing = np.full(max(length, 0), np.nan)
        self.index, self.length, self.bad = index, length, bad

    def take(self) -> RawChunk | None:
        self._convert()
        if not self.parts:
            return None
        fields = [np.concatenate(x) if len(self.parts) > 1 else x[0] for x in zip(*self.parts)]
        chunk = RawChunk(self.first, *fields)
        self.first += len(chunk)
        self.parts, self.converted = [], 0
        return chunk

    def _convert(self) -> None:
        """The messages collected so far, as arrays in the model's joint order, into parts."""
        count = len(self.receive_times)
        if count == 0:
            return
        # each array has ``length`` float64 values in the machine's byte order (rosbags swaps
        # the others), so the buffers hold the values row by row
        values = [
            np.frombuffer(x, np.float64).reshape(count, self.length).copy()
            for x in (self.positions, self.velocities, self.efforts)
        ]
        if self.index is not None:
            values = [v[:, self.index] for v in values]
        # the integers through int64 arrays: half the time of the lists to float64 directly
        sec, nanosec, received = (
            np.fromiter(x, np.int64, count).astype(np.float64)
            for x in (self.seconds, self.nanoseconds, self.receive_times)
        )
        time = np.where((sec != 0.0) | (nanosec != 0.0), seconds(sec, nanosec), received * 1e-9)
        for x in (self.positions, self.velocities, self.efforts, self.seconds, self.nanoseconds, self.receive_times):
            x.clear()
        self.parts.append((time, *values))
        self.converted += count


class _BagSource:
    def __init__(self, recording: Recording):
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore

        self.recording = recording
        path, topic = recording.path, recording.topic
        try:
            self.reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_JAZZY))
            self.reader.open()
        except Exception as error:  # rosbags raises many kinds for a file that is no bag
            raise RecordingError(path, f"not a readable ROS 2 bag ({type(error).__name__}: {error})") from None
        self.connections = [c for c in self.reader.connections if c.topic == topic]
        if not self.connections:
            topics = ", ".join(f"{c.topic} ({c.msgtype})" for c in self.reader.connections) or "none"
            self.reader.close()
            raise RecordingError(path, f"no topic {topic} (topics: {topics}); choose one with --topic")
        kinds = {c.msgtype for c in self.connections}
        if kinds != {JOINT_STATE}:
            self.reader.close()
            raise RecordingError(path, f"{topic} carries {', '.join(sorted(kinds))}, not {JOINT_STATE}")
        self.total = sum(c.msgcount for c in self.connections)

    def chunks(self) -> Iterator[RawChunk]:
        recording, skipped = self.recording, self.recording.skipped
        deserialize = self.reader.typestore.deserialize_cdr
        chunker, chunk_size = _BagChunker(recording), recording.chunk_size
        received = chunker.receive_times
        # the loop's hot calls, bound once
        add_position, add_velocity, add_effort = (
            chunker.positions.__iadd__,
            chunker.velocities.__iadd__,
            chunker.efforts.__iadd__,
        )
        add_seconds, add_nanoseconds, add_time = chunker.seconds.append, chunker.nanoseconds.append, received.append
        names_seen, length, room = None, -1, chunk_size
        try:
            for _, receive_time, raw in self.reader.messages(connections=self.connections):
                try:
                    msg = deserialize(raw, JOINT_STATE)
                except Exception as error:
                    raise RecordingError(
                        recording.path, f"a {recording.topic} message cannot be read ({error})"
                    ) from None
                names, position, velocity, effort = msg.name, msg.position, msg.velocity, msg.effort
                if names != names_seen or not names:
                    names_seen = names
                    if position.dtype != np.float64:  # the buffers take the arrays' bytes
                        raise RecordingError(recording.path, f"rosbags gave {position.dtype} positions, not float64")
                    chunker.layout(*self._mapping(names, len(position)))
                    length, room = chunker.length, chunk_size - chunker.converted
                if chunker.bad is not None:
                    skipped[chunker.bad] += 1
                    continue
                if len(position) != length or len(velocity) != length or len(effort) != length:
                    if len(position) != length or len(velocity) not in (0, length) or len(effort) not in (0, length):
                        skipped["length_mismatch"] += 1
                        continue
                    velocity = velocity if len(velocity) else chunker.missing
                    effort = effort if len(effort) else chunker.missing
                add_position(position)
                add_velocity(velocity)
                add_effort(effort)
                stamp = msg.header.stamp
                add_seconds(stamp.sec)
                add_nanoseconds(stamp.nanosec)
                add_time(receive_time)
                if len(received) >= room:
                    chunk, room = chunker.take(), chunk_size
                    yield chunk
            chunk = chunker.take()
            if chunk is not None:
                yield chunk
        except RecordingError:
            raise
        except Exception as error:
            raise RecordingError(recording.path, f"reading failed ({type(error).__name__}: {error})") from None
        finally:
            self.reader.close()

    def _mapping(self, names, count: int):
        """(index into the message's arrays or None for as-is, their length, why skipped or None)."""
        try:
            index, length = self.recording.order.for_values(names, count)
        except BadMessage as error:
            return None, -1, error.kind
        if list(index) == list(range(length)):
            return None, length, None
        return np.array(index, dtype=np.intp), length, None


class _CsvSource:
    def __init__(self, recording: Recording):
        self.recording = recording
        path = recording.path
        if not path.is_file():
            raise RecordingError(path, "not a regular file")
        self.total = _scan(path) - 1
        try:
            with open(path, newline="") as stream:
                header = next(csv.reader(stream), None)
        except (OSError, UnicodeDecodeError, csv.Error) as error:
            raise RecordingError(path, f"cannot be read ({error})") from None
        if not header:
            raise RecordingError(path, "empty: expected a header row (time, position_<joint>, ..., effort_<joint>)")
        where = {name.strip(): i for i, name in enumerate(header)}
        joints = recording.order.joint_names
        needed = [("time", None)] + [(field, (k, j)) for field in ("position", "effort") for k, j in enumerate(joints)]
        found = [_column(where, field, joint) for field, joint in needed]
        missing = [_name(field, joint) for (field, joint), column in zip(needed, found) if column is None]
        if missing:
            raise RecordingError(path, f"no column {', '.join(missing)} (columns: {', '.join(header)})")
        velocity = [_column(where, "velocity", (k, j)) for k, j in enumerate(joints)]
        self.has_velocity = all(column is not None for column in velocity)
        self.columns = found + (velocity if self.has_velocity else [])
        self.width = len(header)

    def chunks(self) -> Iterator[RawChunk]:
        try:
            yield from self._chunks()
        except (OSError, UnicodeDecodeError, csv.Error) as error:
            raise RecordingError(self.recording.path, f"cannot be read ({error})") from None

    def _chunks(self) -> Iterator[RawChunk]:
        recording, n = self.recording, self.recording.n
        first = 0
        with open(recording.path, newline="") as stream:
            next(stream)
            line_number = 1
            while True:
                lines = [line for line in islice(stream, recording.chunk_size) if line.strip()]
                if not lines:
                    return
                values = self._parse(lines, line_number + 1)
                line_number += len(lines)
                velocity = values[:, 1 + 2 * n :] if self.has_velocity else np.full((len(lines), n), np.nan)
                yield RawChunk(first, values[:, 0], values[:, 1 : 1 + n], velocity, values[:, 1 + n : 1 + 2 * n])
                first += len(lines)

    def _parse(self, lines: list[str], first_line: int) -> np.ndarray:
        try:
            table = np.loadtxt(lines, delimiter=",", ndmin=2)
            if table.shape[1] == self.width:
                return table[:, self.columns]
        except ValueError:
            pass
        rows = []
        for k, row in enumerate(csv.reader(lines)):
            if len(row) != self.width:
                raise RecordingError(
                    self.recording.path, f"line {first_line + k}: {len(row)} cells, the header has {self.width}"
                )
            try:
                rows.append([float(row[i]) if row[i].strip() else np.nan for i in self.columns])
            except ValueError:
                bad = next(row[i] for i in self.columns if not _is_number(row[i]))
                raise RecordingError(
                    self.recording.path, f"line {first_line + k}: not a number: {bad[:40]!r}"
                ) from None
        return np.array(rows, dtype=float).reshape(-1, len(self.columns))


CSV_NAMES = {
    "time": ("time", "t"),
    "position": ("position", "q"),
    "velocity": ("velocity", "qd"),
    "effort": ("effort", "tau"),
}  # each field's column prefixes: the long name first


def _name(field: str, joint) -> str:
    return field if joint is None else f"{field}_{joint[1]}"


def _column(where: dict, field: str, joint) -> int | None:
    """The column of ``field`` of joint (index, name) (None: time): by the long or short
    prefix, with the joint's name or its number from 1."""
    for prefix in CSV_NAMES[field]:
        names = [prefix] if joint is None else [f"{prefix}_{joint[1]}", f"{prefix}_{joint[0] + 1}"]
        for name in names:
            if name in where:
                return where[name]
    return None


def _is_number(text: str) -> bool:
    try:
        float(text) if text.strip() else None
        return True
    except ValueError:
        return False


def _scan(path: Path) -> int:
    """A CSV file's non-blank lines, counted in blocks; a line over CSV_LINE_LIMIT bytes or a
    NUL byte (binary data) refused before anything is parsed."""
    lines, carry, pending = 0, 0, False  # non-blank lines ended, bytes and content of the open one
    try:
        with open(path, "rb") as stream:
            while block := stream.read(1 << 20):
                if b"\0" in block:
                    raise RecordingError(path, "binary data (a NUL byte): not a CSV file")
                parts = block.split(b"\n")
                for k, part in enumerate(parts):
                    if len(part) + (carry if k == 0 else 0) > CSV_LINE_LIMIT:
                        raise RecordingError(
                            path,
                            f"line {lines + k + 1}: longer than {CSV_LINE_LIMIT} bytes: not a CSV file of joint states",
                        )
                if len(parts) > 1:
                    lines += (pending or bool(parts[0].strip())) + sum(1 for x in parts[1:-1] if x.strip())
                    carry, pending = len(parts[-1]), bool(parts[-1].strip())
                else:
                    carry, pending = carry + len(parts[0]), pending or bool(parts[0].strip())
    except OSError as error:
        raise RecordingError(path, f"cannot be read ({error.strerror})") from None
    return lines + pending


# -- writing: the recordings `record` makes, read back by the readers above ----------------


def open_bag(path: Path):
    """rosbags' writer of a new ROS 2 bag directory (.mcap) at ``path`` (ValueError when it
    exists); give each topic a connection (``bag_connection``), then ``write``, ``close``."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    if path.exists():
        raise ValueError(f"{path}: exists already; give a new name")
    writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    return writer


def bag_connection(writer, topic: str, type_name: str):
    """A topic of ``type_name`` (e.g. sensor_msgs/msg/JointState) in the bag ``writer`` writes,
    its messages as CDR bytes (the ROS 2 Jazzy types)."""
    from rosbags.typesys import Stores, get_typestore

    return writer.add_connection(topic, type_name, typestore=get_typestore(Stores.ROS2_JAZZY))
