"""id_node's virtual force sensor: the observer's external torques as the wrench on the flange.

Publishes    external_wrench   geometry_msgs/WrenchStamped: the wrench F = (force [N], torque
                               [N m] about the flange origin) on the flange with J(q)^T F =
                               the observer's external torques (core.monitoring.wrench: least
                               squares, damped near a singularity), for every joint state with
                               efforts (while anything subscribes), stamped like the input;
                               ``header.frame_id`` the tip link (``flange`` for a model of
                               parameters, the URDF's tip link for a URDF's), or with
                               ``external_wrench.frame: base`` the base link, the same wrench
                               in its axes (the torque still about the flange origin)

The /diagnostics status says WARN near a singularity (J's smallest singular value below
core.monitoring.wrench.SINGULAR_THRESHOLD, there or at any wrench since the last report):
the estimate is then damped, and poor along the direction the arm cannot push.
"""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import WrenchStamped
from rclpy.node import Node

from irb140_dynamics.core.monitoring.wrench import FRAMES, SINGULAR_THRESHOLD, FlangeWrench, flange_wrench
from irb140_dynamics.ros.messages.wrench import fill_wrench
from irb140_dynamics.ros.parameters.specs import Spec
from irb140_dynamics.ros.runtime.listened import ListenedPublisher

WRENCH_PARAMETERS = [
    Spec(
        "external_wrench.frame",
        "tip",
        "axes of external_wrench: 'tip' (the tip link's, e.g. flange) or 'base' (the base link's); "
        "the torque is about the flange origin in both",
    ),
]


def check_wrench_frame(values: dict) -> str:
    frame = values["external_wrench.frame"]
    if frame not in FRAMES:
        raise ValueError(f"external_wrench.frame: must be one of {', '.join(FRAMES)}; got {frame!r}")
    return frame


class WrenchSensor:
    """Publishes the flange wrench of each observed sample; remembers the last sample and the
    smallest singular value of J since the last report for /diagnostics."""

    def __init__(self, node: Node, depth: int):
        self._publisher = ListenedPublisher(node, WrenchStamped, "external_wrench", depth)
        self._msg = WrenchStamped()
        self._sample = None  # (model, q, r) of the last observed joint state
        self._smallest: float | None = None  # smallest sigma_min of J since the last report

    def update(self, model, frame: str, links: tuple[str, str], stamp, q, r) -> FlangeWrench | None:
        """One observed sample (q [rad], r [N m]): the wrench published, if anything
        subscribes (else None). ValueError if it is not finite (nothing published)."""
        self._sample = (model, q, r)
        if not self._publisher.subscribers:
            return None
        wrench = flange_wrench(model, q, r, frame)
        self._note(wrench)
        base, tip = links
        self._publisher.publish(
            fill_wrench(self._msg, stamp, tip if frame == "tip" else base, wrench.force, wrench.torque)
        )
        return wrench

    def forget(self) -> None:
        """A new model: the last sample belongs to the old one."""
        self._sample, self._smallest = None, None

    def _note(self, wrench: FlangeWrench) -> None:
        sigma = wrench.smallest_singular_value
        if self._smallest is None or sigma < self._smallest:
            self._smallest = sigma

    def status(self, node_name: str, hardware_id: str) -> DiagnosticStatus:
        """WARN near a singularity (now, or at a wrench since the last report), else OK; the
        smallest singular value of J in the values. Starts a new period."""
        status = DiagnosticStatus(name=f"{node_name}: external wrench", hardware_id=hardware_id)
        if self._sample is None:
            status.level, status.message = DiagnosticStatus.OK, "no efforts received: no wrench estimated"
            return status
        model, q, r = self._sample
        try:
            now = flange_wrench(model, q, r, "tip")
        except ValueError as error:
            status.level, status.message = DiagnosticStatus.WARN, f"no wrench at the last joint state ({error})"
            return status
        smallest = (
            now.smallest_singular_value if self._smallest is None else min(self._smallest, now.smallest_singular_value)
        )
        self._smallest = None
        status.values = [
            KeyValue(key="smallest singular value of J, now", value=f"{now.smallest_singular_value:.4f}"),
            KeyValue(key="smallest singular value of J since last report", value=f"{smallest:.4f}"),
        ]
        if smallest < SINGULAR_THRESHOLD:
            where = "now" if now.near_singularity else "since the last report"
            status.level = DiagnosticStatus.WARN
            status.message = (
                f"near a singularity {where}: smallest singular value of J {smallest:.4f} < {SINGULAR_THRESHOLD:g}; "
                "the wrench estimate is damped and poor along the direction the arm cannot push"
            )
        else:
            status.level, status.message = DiagnosticStatus.OK, f"smallest singular value of J {smallest:.4f}"
        return status
