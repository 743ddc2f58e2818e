"""Random inputs for the fuzz tests of the nodes: joint states, references and parameter sets,
valid and invalid, each labelled with what a node must make of it."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

NAMES = [f"joint_{i}" for i in range(1, 7)]
BAD_NUMBERS = (math.nan, math.inf, -math.inf)


@dataclass
class Labelled:
    """A message and what it means: ``state`` (q, qd[, qdd]) of the model's joints in model
    order when its structure is valid (the torques there decide the rest), None when the
    node must drop it; ``ignored``: about none of the model's joints."""

    msg: object
    state: tuple | None
    ignored: bool = False


class Fuzzer:
    def __init__(self, seed: int):
        self.rng = np.random.default_rng(seed)
        self.stamp_ns = 1_000_000_000

    def _values(self, n, scale):
        return (self.rng.uniform(-scale, scale, n)).tolist()

    def _absurd(self, n):
        """Finite but absurd velocities: sometimes the torques overflow, sometimes not."""
        return (self.rng.choice([1.0, -1.0], n) * 10.0 ** self.rng.uniform(100, 200, n)).tolist()

    def _stamp(self, msg):
        self.stamp_ns += int(self.rng.choice([1, 1_000_000, 2_000_000, 0, -1_000_000]))  # repeats, going back
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(max(self.stamp_ns, 0), 1_000_000_000)

    def joint_state(self) -> Labelled:
        rng = self.rng
        q, qd = self._values(6, 4.0), self._values(6, 5.0)
        if rng.random() < 0.1:
            qd = self._absurd(6)
        with_velocity = rng.random() < 0.8
        order = rng.permutation(6).tolist()
        names = [NAMES[i] for i in order]
        positions, velocities = [q[i] for i in order], [qd[i] for i in order]
        extra = int(rng.integers(0, 3))
        for k in range(extra):  # joints the model does not have, with any values
            names.append(f"gripper_{k}" if rng.random() < 0.7 else f"tool_{rng.integers(1 << 30)}")
            positions.append(float(rng.choice([0.01, math.nan, math.inf, 1e300])))
            velocities.append(float(rng.choice([0.0, math.nan, -math.inf])))
        msg = JointState(name=names, position=positions, velocity=velocities if with_velocity else [])
        if rng.random() < 0.2:
            msg.effort = [float(x) for x in rng.choice([0.0, math.nan, 1e308], len(names))]
        self._stamp(msg)
        state = (q, qd if with_velocity else [0.0] * 6)
        defect = rng.choice(
            ["none"] * 9
            + [
                "nan_q",
                "nan_qd",
                "short_q",
                "short_qd",
                "long_effort",
                "duplicate",
                "missing",
                "unnamed_short",
                "empty",
                "other_only",
                "positional",
            ]
        )
        if defect == "none":
            return Labelled(msg, state)
        if defect == "positional":  # no names, the model's length: positional
            return Labelled(JointState(position=q, velocity=qd if with_velocity else []), state)
        if defect == "other_only":
            return Labelled(JointState(name=["gripper_left", "gripper_right"], position=[0.0, math.nan]), None, True)
        i = names.index(NAMES[int(rng.integers(6))])
        if defect == "nan_q":
            msg.position[i] = float(rng.choice(BAD_NUMBERS))
        elif defect == "nan_qd":
            if not with_velocity:
                msg.velocity = velocities
            msg.velocity[i] = float(rng.choice(BAD_NUMBERS))
        elif defect == "short_q":
            msg.position = msg.position[:-1]
        elif defect == "short_qd":
            msg.velocity = velocities[:-1]
        elif defect == "long_effort":
            msg.effort = [0.0] * (len(names) + 1)
        elif defect == "duplicate":
            msg.name[i] = msg.name[(i + 1) % 6]
        elif defect == "missing":
            del msg.name[i], msg.position[i]
            msg.velocity = [v for k, v in enumerate(msg.velocity) if k != i]
        elif defect == "unnamed_short":
            msg = JointState(position=q[:5])
        elif defect == "empty":
            msg = JointState()
        return Labelled(msg, None)

    def reference(self) -> Labelled:
        rng = self.rng
        q, qd, qdd = self._values(6, 3.0), self._values(6, 3.0), self._values(6, 10.0)
        kind = rng.choice(["full", "no_qdd", "no_qd", "empty", "absurd", "nan", "missing", "short_qdd"])
        if kind == "empty":
            return Labelled(JointTrajectory(), ("clear",))
        if kind == "absurd":
            qd = self._absurd(6)
        point = JointTrajectoryPoint(
            positions=q,
            velocities=[] if kind == "no_qd" else qd,
            accelerations=[] if kind in ("no_qd", "no_qdd") else qdd,
        )
        names = list(NAMES)
        state = (q, [0.0] * 6 if kind == "no_qd" else qd, None if kind in ("no_qd", "no_qdd") else qdd)
        if kind == "nan":
            point.positions[int(rng.integers(6))] = math.nan
            state = None
        elif kind == "missing":
            names, point.positions = names[:5], q[:5]
            state = None
        elif kind == "short_qdd":
            point.accelerations = qdd[:4]
            state = None
        return Labelled(JointTrajectory(joint_names=names, points=[point]), state)


def parameter_set(rng, joints=NAMES, model_structure=True) -> tuple[list[Parameter], bool]:
    """1 to 3 parameters and whether the set is valid (all of them valid)."""
    valid_makers = [
        lambda: Parameter("payload.mass", value=float(rng.uniform(0.0, 20.0))),
        lambda: Parameter("payload.com", value=rng.uniform(-0.2, 0.2, 3).tolist()),
        lambda: Parameter("gravity", value=(rng.normal(size=3) * 5.0).tolist()),
    ]
    invalid_makers = [
        lambda: Parameter("payload.mass", value=float(rng.choice([-1.0, math.nan, math.inf, 1e300]))),
        lambda: Parameter("payload.com", value=[0.0, 0.0]),
        lambda: Parameter("payload.com", value=[0.0, math.nan, 0.0]),
        lambda: Parameter("payload.inertia", value=[1.0, 1.0, 5.0, 0.0, 0.0, 0.0]),
        lambda: Parameter("gravity", value=[0.0, 0.0, 1e9]),
        lambda: Parameter("payload.mass", value="heavy"),
        lambda: Parameter("joint_names", value=["a", "b"]),
        lambda: Parameter("qos.depth", value=5),
        lambda: Parameter(str(rng.choice(["", "payload.mas", "joint_9.dh"])), value=1.0),
    ]
    if model_structure:
        valid_makers += [
            lambda: Parameter(f"{rng.choice(joints)}.link.mass", value=float(rng.uniform(0.0, 40.0))),
            lambda: Parameter(f"{rng.choice(joints)}.position_limits", value=[-1.0, float(rng.uniform(0.0, 3.0))]),
        ]
        invalid_makers += [lambda: Parameter(f"{rng.choice(joints)}.dh", value=[0.0, 0.0, 2e3, 0.0])]
    count = int(rng.integers(1, 4))
    valid = rng.random() < 0.5
    params = [valid_makers[int(rng.integers(len(valid_makers)))]() for _ in range(count)]
    if not valid:
        params[int(rng.integers(count))] = invalid_makers[int(rng.integers(len(invalid_makers)))]()
    names = [p.name for p in params]
    if len(set(names)) != len(names):  # the same name twice: the last one counts; keep it simple
        return parameter_set(rng, joints, model_structure)
    return params, valid
