"""id_node's external-torque estimate and collision flag: the ROS side of core.monitoring.observer.

Publishes    external_torques   sensor_msgs/JointState, effort = the observer's residual r
                                [N m], model joint order, stamped like the input
             collision          std_msgs/Bool, reliable, transient local, depth 1: true while
                                any |r_j| exceeds joint j's collision_threshold (0 = off)

The diagnostics status reports any collision since the last report (the peak |r_j| of each
joint over its threshold), so that one shorter than the 1 s period still shows as ERROR.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool

from irb140_dynamics.core.monitoring.observer import MomentumObserver
from irb140_dynamics.ros.messages.joint_messages import publish_efforts
from irb140_dynamics.ros.messages.joint_state_cdr import EffortMessage
from irb140_dynamics.ros.parameters.specs import MAX_TORQUE, Spec
from irb140_dynamics.ros.runtime.listened import ListenedPublisher

MAX_GAIN = 1e4  # 1/s: beyond any sampling rate a joint state stream has
OBSERVER_GAP = 0.1  # s: a longer gap between stamps restarts the observer
RESTARTS = {  # MomentumObserver.restarted: what restarted it
    "gap": f"a gap of more than {OBSERVER_GAP:g} s between joint_states stamps",
    "repeated_stamp": "a repeated joint_states stamp",
    "older_stamp": "a joint_states stamp older than the one before",
}

COLLISION_PARAMETERS = [
    Spec(
        "collision.observer_gain",
        100.0,
        "gain K of the momentum observer: external torques are seen through a lag of time constant 1/K",
        "1/s",
        minimum=1e-3,
        maximum=MAX_GAIN,
    ),
]


def collision_threshold_specs(joint_names) -> list[Spec]:
    return [
        Spec(
            f"{name}.collision_threshold",
            0.0,
            "a collision is flagged while |external torque| exceeds this; 0 = off",
            "N m",
            minimum=0.0,
            maximum=MAX_TORQUE,
        )
        for name in joint_names
    ]


@dataclass(frozen=True)
class CollisionSettings:
    gain: float  # 1/s
    thresholds: np.ndarray  # N m, 0 = off


def build_collision_settings(values: dict, joint_names) -> CollisionSettings:
    thresholds = np.array([values[f"{name}.collision_threshold"] for name in joint_names], dtype=float)
    return CollisionSettings(values["collision.observer_gain"], thresholds)


class CollisionMonitor:
    """Runs the observer on joint states that carry efforts; publishes r and the flag."""

    def __init__(self, node: Node, joint_names, depth: int):
        self._names = list(joint_names)
        self._external_msg = EffortMessage(self._names)
        self._external_pub = ListenedPublisher(node, JointState, "external_torques", depth)
        latched = QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
        )
        self._collision_pub = node.create_publisher(Bool, "collision", latched)
        self.colliding: list[int] = []  # indices of the joints over their thresholds
        self._peaks = [0.0] * len(self._names)  # N m: the largest |r_j| over threshold since the last report
        self._residual = None
        self._publish_flag(False)

    def use(self, model, settings: CollisionSettings) -> None:
        """A new model or new gains: the observer starts again (named as the model's joints)."""
        if list(model.joint_names) != self._names:
            self._names = list(model.joint_names)
            self._external_msg = EffortMessage(self._names)
            self._residual = None
            self._peaks = [0.0] * len(self._names)  # (the flag: at the next sample, as after any restart)
        self._observer = MomentumObserver(model, settings.gain, OBSERVER_GAP)
        self._thresholds = settings.thresholds.tolist()
        self._joints = range(len(self._names))

    def reset(self) -> None:
        self._observer.reset()

    @property
    def residual(self) -> list[float] | None:
        """The external torques of the last joint state with efforts [N m], None before one."""
        return self._residual

    def update(self, t: float, q, qd, effort, g, stamp, terms=None) -> str | None:
        """One joint state with efforts: publish the residual, and the flag when it changes
        (``terms``: see MomentumObserver.advance). What restarted the observer at this
        sample (a key of RESTARTS), or None. ValueError (observer reset) if the residual
        is not finite."""
        observer = self._observer
        r = observer.advance(t, q, qd, effort, g, terms)
        self._residual = r
        publish_efforts(self._external_pub, self._external_msg, stamp, r)
        colliding = [j for j, x, limit in zip(self._joints, r, self._thresholds) if 0.0 < limit < abs(x)]
        if colliding:
            peaks = self._peaks
            for j in colliding:
                if abs(r[j]) > peaks[j]:
                    peaks[j] = abs(r[j])
        if bool(colliding) != bool(self.colliding):
            self._publish_flag(bool(colliding))
        self.colliding = colliding
        return observer.restarted

    def _publish_flag(self, value: bool) -> None:
        self._collision_pub.publish(Bool(data=value))

    def status(self, node_name: str, hardware_id: str) -> DiagnosticStatus:
        """ERROR while colliding or after a collision since the last report (naming the
        joints and torques: now, or the peak |r_j| since); OK otherwise. Starts a new period."""
        status = DiagnosticStatus(name=f"{node_name}: collision", hardware_id=hardware_id)
        names, r, peaks = self._names, self._residual, self._peaks
        self._peaks = [0.0] * len(names)
        if r is None:
            status.level, status.message = DiagnosticStatus.OK, "no efforts received: observer idle"
            return status
        earlier = [j for j, peak in enumerate(peaks) if peak > 0.0 and j not in self.colliding]
        since = ", ".join(f"{names[j]} {peaks[j]:.2f} N m" for j in earlier)
        if self.colliding:
            status.level = DiagnosticStatus.ERROR
            status.message = "collision: " + ", ".join(f"{names[j]} {r[j]:.2f} N m" for j in self.colliding)
            if earlier:
                status.message += f"; since last report: {since}"
        elif earlier:
            status.level, status.message = DiagnosticStatus.ERROR, f"collision since last report: {since}"
        else:
            status.level, status.message = DiagnosticStatus.OK, "no collision"
        status.values = [
            KeyValue(key=f"{name} external torque [N m]", value=f"{value:.3f}") for name, value in zip(names, r)
        ] + [
            KeyValue(key=f"{names[j]} peak |external torque| since last report [N m]", value=f"{peak:.3f}")
            for j, peak in enumerate(peaks)
            if peak > 0.0
        ]
        return status
