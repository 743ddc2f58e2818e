"""Reading recordings: ROS 2 bags (.mcap, .db3) through rosbags, CSV files, and their errors."""

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from irb140_dynamics.core import irb140
from irb140_dynamics.identification.pipeline import IdentificationSettings, identify
from irb140_dynamics.identification.recording import Recording, RecordingError

from ..support.synthetic_arm import write_bag, write_csv

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
JointState = TYPESTORE.types["sensor_msgs/msg/JointState"]
Header = TYPESTORE.types["std_msgs/msg/Header"]
Time = TYPESTORE.types["builtin_interfaces/msg/Time"]
NAMES = ("a", "b", "c")
T0 = 1_700_000_000 * 10**9


def message(k, names=NAMES, position=None, velocity=(), effort=None, stamped=True):
    position = [k + 0.1 * i for i in range(len(names))] if position is None else position
    effort = [10 * k + i for i in range(len(names))] if effort is None else effort
    ns = T0 + k * 10**7
    stamp = Time(ns // 10**9, ns % 10**9) if stamped else Time(0, 0)
    msg = JointState(
        Header(stamp, ""), list(names), np.array(position, float), np.array(velocity, float), np.array(effort, float)
    )
    return ns, TYPESTORE.serialize_cdr(msg, JointState.__msgtype__)


def read(path, **kwargs):
    recording = Recording(path, NAMES, **kwargs)
    chunks = list(recording.chunks())
    return recording, chunks


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_bag_joints_matched_by_name_others_counted(tmp_path, storage):
    shuffled = ("c", "gripper", "a", "b")
    messages = [
        message(0),
        message(
            1, names=shuffled, position=[1.2, 9.0, 1.0, 1.1], effort=[12.0, 99.0, 10.0, 11.0], velocity=[3, 9, 1, 2]
        ),
        message(2, names=("gripper",), position=[0.5], effort=[1.0]),  # another device's joints
        message(3, names=(), position=[3.0, 3.1, 3.2], effort=[30.0, 31.0, 32.0], stamped=False),  # positional
        message(4, effort=[]),  # no effort: NaN
        message(5, names=("a", "b"), position=[5.0, 5.1], effort=[50.0, 51.0]),  # c missing
        message(6, position=[6.0, 6.1]),  # too short
        message(7),
    ]
    path = write_bag(tmp_path / "bag", messages, storage=storage)
    bag_file = next(path.glob("*.mcap" if storage == "mcap" else "*.db3"))
    for where in (path, bag_file):  # the bag directory or its storage file
        recording, chunks = read(where, chunk_size=2)
        assert recording.total == 8
        t = np.concatenate([c.time for c in chunks])
        q = np.vstack([c.position for c in chunks])
        tau = np.vstack([c.effort for c in chunks])
        qd = np.vstack([c.velocity for c in chunks])
        assert [c.first for c in chunks] == [0, 2, 4]
        np.testing.assert_allclose(q, [[k, k + 0.1, k + 0.2] for k in (0, 1, 3, 4, 7)], atol=1e-12)
        np.testing.assert_allclose(tau[[0, 1, 2, 4]], [[0, 1, 2], [10, 11, 12], [30, 31, 32], [70, 71, 72]])
        assert np.isnan(tau[3]).all() and np.isnan(qd[0]).all()
        np.testing.assert_allclose(qd[1], [1, 2, 3])
        np.testing.assert_allclose(t - t[0], [0.0, 0.01, 0.03, 0.04, 0.07], atol=1e-6)  # header or receive time
        assert dict(recording.skipped) == {"other_joints": 1, "missing_joints": 1, "length_mismatch": 1}


def test_csv_columns_by_name_with_velocity_and_gaps(tmp_path):
    path = tmp_path / "run.csv"
    path.write_text(
        "effort_b,time,position_a,extra,position_c,position_b,effort_a,effort_c,velocity_a,velocity_b,velocity_c\n"
        "1.5,0.0,0.1,x,0.3,0.2,1.0,2.0,0.0,0.0,0.0\n"
        "\n"
        "2.5,0.01,0.11,y,0.31,0.21,,3.0,1.0,2.0,3.0\n"
    )
    recording, (chunk,) = read(path)
    assert recording.total == 2
    np.testing.assert_allclose(chunk.time, [0.0, 0.01])
    np.testing.assert_allclose(chunk.position, [[0.1, 0.2, 0.3], [0.11, 0.21, 0.31]])
    np.testing.assert_allclose(chunk.effort[0], [1.0, 1.5, 2.0])
    assert np.isnan(chunk.effort[1, 0])
    np.testing.assert_allclose(chunk.velocity[1], [1.0, 2.0, 3.0])


def test_csv_without_velocity_in_chunks(tmp_path):
    from ..support.synthetic_arm import Samples

    t = np.arange(7) * 0.01
    q = np.outer(t, [1.0, 2.0, 3.0])
    samples = Samples(t, q, q, -q, -q)
    recording, chunks = read(write_csv(tmp_path / "run.csv", samples, NAMES), chunk_size=3)
    assert [len(c) for c in chunks] == [3, 3, 1] and [c.first for c in chunks] == [0, 3, 6]
    np.testing.assert_allclose(np.vstack([c.effort for c in chunks]), -q)
    assert all(np.isnan(c.velocity).all() for c in chunks)


@pytest.mark.parametrize(
    "name, content, problem",
    [
        ("none.csv", None, "no such file"),
        ("data.txt", "1,2,3\n", "not a ROS 2 bag"),
        ("empty.csv", "", "empty"),
        ("few.csv", "time,position_a,position_b,position_c,effort_a,effort_b\n", "no column effort_c"),
        (
            "bad.csv",
            "time,position_a,position_b,position_c,effort_a,effort_b,effort_c\n0,1,2,3,4,5,6\n0.1,1,2,oops,4,5,6\n",
            "line 3: not a number",
        ),
        (
            "short.csv",
            "time,position_a,position_b,position_c,effort_a,effort_b,effort_c\n0,1,2,3,4,5\n",
            "line 2: 6 cells",
        ),
        ("garbage.mcap", "this is not an mcap file", "not a readable ROS 2 bag"),
    ],
)
def test_bad_files_give_one_error_naming_the_file(tmp_path, name, content, problem):
    path = tmp_path / name
    if content is not None:
        path.write_text(content)
    with pytest.raises(RecordingError) as error:
        read(path)
    assert str(error.value).startswith(f"{path}: ") and problem in str(error.value), str(error.value)


def test_wrong_topic_lists_the_bag_topics(tmp_path):
    path = write_bag(tmp_path / "bag", [message(0)], topic="/arm/joint_states")
    with pytest.raises(
        RecordingError,
        match=r"no topic /joint_states \(topics: .*/arm/joint_states "
        r"\(sensor_msgs/msg/JointState\).*--topic",
    ):
        read(path)
    with pytest.raises(
        RecordingError, match="/rosout_like carries std_msgs/msg/String, not sensor_msgs/msg/JointState"
    ):
        read(path, topic="/rosout_like")
    recording, chunks = read(path, topic="/arm/joint_states")
    assert len(chunks[0]) == 1


def test_a_bag_of_other_joints_only_is_refused_by_identify(tmp_path):
    path = write_bag(tmp_path / "bag", [message(k, names=("x", "y")) for k in range(5)])
    with pytest.raises(RecordingError, match="no usable joint states of the model's joints \\(5 other joints\\)"):
        identify(irb140(), path, IdentificationSettings())


def test_recording_without_effort_is_refused_by_identify(tmp_path):
    names = irb140().joint_names
    path = write_bag(tmp_path / "bag", [message(k, names=names, position=[0.1 * k] * 6, effort=[]) for k in range(50)])
    with pytest.raises(RecordingError, match="no sample has efforts"):
        identify(irb140(), path, IdentificationSettings())
