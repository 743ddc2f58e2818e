"""A synthetic 'true' IRB-140 and recordings of it, for the identification tests and bench.

The true arm is the report's arm with each link's mass changed by up to +-30 % (its
inertia scaled with it), its centre of mass moved by up to 3 cm, and viscous friction,
Coulomb friction and armature on every joint. Driven along an excitation trajectory, its
torques come from rnea on the true model, plus Gaussian noise of 1 % of each joint's peak
torque; positions are quantised to 1e-5 rad (an encoder's resolution).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from irb140_dynamics.core import Friction, RigidBody, RobotModel, irb140, rnea_batch

VISCOUS = np.array([6.0, 8.0, 4.0, 1.2, 1.0, 0.6])  # N m s/rad
COULOMB = np.array([9.0, 12.0, 7.0, 2.5, 2.0, 1.2])  # N m
ARMATURE = np.array([1.2, 1.5, 0.6, 0.12, 0.1, 0.04])  # kg m^2
QUANTUM = 1e-5  # rad
NOISE = 0.01  # of each joint's peak torque


def true_arm(seed: int = 0) -> RobotModel:
    rng = np.random.default_rng(seed)
    joints = []
    for j, viscous, coulomb, armature in zip(irb140().joints, VISCOUS, COULOMB, ARMATURE):
        link = j.link
        if link.mass > 0:
            factor = rng.uniform(0.7, 1.3)
            direction = rng.normal(size=3)
            shift = direction / np.linalg.norm(direction) * rng.uniform(0.0, 0.03)
            link = RigidBody(
                link.mass * factor, tuple(np.add(link.com, shift)), tuple(factor * x for x in link.inertia)
            )
        spread = rng.uniform(0.7, 1.3, 3)
        joints.append(
            replace(
                j, link=link, friction=Friction(viscous * spread[0], coulomb * spread[1]), armature=armature * spread[2]
            )
        )
    return replace(irb140(), joints=tuple(joints))


@dataclass(frozen=True, eq=False)
class Samples:
    time: np.ndarray  # (N,) s
    position: np.ndarray  # (N, n) quantised
    velocity: np.ndarray  # (N, n) exact
    effort: np.ndarray  # (N, n) with noise
    true_effort: np.ndarray

    @property
    def peak(self) -> np.ndarray:
        return np.abs(self.true_effort).max(axis=0)


def drive(arm: RobotModel, trajectory, rate: float, duration: float, seed: int = 1, start: float = 0.0) -> Samples:
    """The arm along ``trajectory`` (repeated) for ``duration`` s at ``rate`` Hz."""
    t = start + np.arange(int(round(duration * rate))) / rate
    Q, QD, QDD = trajectory.evaluate(t)
    tau = rnea_batch(arm, Q, QD, QDD)
    peak = np.abs(tau).max(axis=0)
    noise = np.random.default_rng(seed).normal(size=tau.shape) * NOISE * peak
    return Samples(t, np.round(Q / QUANTUM) * QUANTUM, QD, tau + noise, tau)


def joint_state_messages(samples: Samples, names, with_velocity: bool, typestore):
    """(stamp ns, serialised sensor_msgs/JointState) of every sample."""
    JointState = typestore.types["sensor_msgs/msg/JointState"]
    Header = typestore.types["std_msgs/msg/Header"]
    Time = typestore.types["builtin_interfaces/msg/Time"]
    empty = np.zeros(0)
    stamp0 = 1_700_000_000 * 10**9
    for k in range(len(samples.time)):
        ns = stamp0 + int(round(samples.time[k] * 1e9))
        msg = JointState(
            Header(Time(ns // 10**9, ns % 10**9), ""),
            list(names),
            samples.position[k],
            samples.velocity[k] if with_velocity else empty,
            samples.effort[k],
        )
        yield ns, typestore.serialize_cdr(msg, JointState.__msgtype__)


def write_bag(
    path: Path, messages, storage: str = "mcap", topic: str = "/joint_states", extra_topic: bool = True
) -> Path:
    """A rosbag2 directory at ``path`` with ``messages`` (stamp ns, raw) on ``topic``."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    typestore = get_typestore(Stores.ROS2_JAZZY)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        connection = writer.add_connection(topic, "sensor_msgs/msg/JointState", typestore=typestore)
        if extra_topic:
            other = writer.add_connection("/rosout_like", "std_msgs/msg/String", typestore=typestore)
            String = typestore.types["std_msgs/msg/String"]
            writer.write(other, 1, typestore.serialize_cdr(String("hello"), "std_msgs/msg/String"))
        for ns, raw in messages:
            writer.write(connection, ns, raw)
    return path


def write_csv(path: Path, samples: Samples, names, with_velocity: bool = False) -> Path:
    columns = ["time"] + [f"position_{n}" for n in names] + [f"effort_{n}" for n in names]
    blocks = [samples.time[:, None], samples.position, samples.effort]
    if with_velocity:
        columns += [f"velocity_{n}" for n in names]
        blocks.append(samples.velocity)
    np.savetxt(path, np.hstack(blocks), delimiter=",", header=",".join(columns), comments="", fmt="%.10g")
    return path
