"""id_node's RViz markers: the joints' loads, the payload, the external force, a collision.

Publishes    ~/markers   visualization_msgs/MarkerArray, at most ``markers.rate`` Hz (0: off),
                         only after new joint states (a stopped stream's markers expire after
                         their lifetime, LIFETIME_PERIODS periods), in the base link's frame
                         (the URDF's name: robot_state_publisher's TF lines up)

Each marker keeps its namespace and id (RViz updates it in place):

- ``joint_load`` j: a sphere at joint j's origin (nested in those of earlier joints at the same
  place, e.g. a wrist's, its label stacked above theirs) coloured by |tau_j| / limit_j (the measured
  effort when the joint state has efforts, else the feed-forward torque; the limit the
  payload check uses), green 0, yellow 0.7, red 1 and above, grey without a limit;
  ``joint_label`` j: its text, e.g. ``joint_3 81 % (85.2 N m)`` (core.monitoring.display);
- ``payload`` 0: a sphere at the payload's centre of mass, its size from its mass (when it has one);
- ``external_force`` 0: when efforts are measured, the estimated force on the flange as an
  arrow from the flange origin, ARROW_PER_NEWTON (0.01 m/N) long, and ``external_force``
  1 its text (N);
- ``collision`` 0: while ``collision`` is true, a red text above the flange naming the joints.

Nothing is published before a model is loaded, nor a marker that is not finite.
"""

from __future__ import annotations

import math

import numpy as np
from builtin_interfaces.msg import Duration
from geometry_msgs.msg import Point
from rclpy.node import Node
from visualization_msgs.msg import Marker, MarkerArray

from irb140_dynamics.core.kinematics import flange_pose, joint_origins
from irb140_dynamics.core.monitoring import display
from irb140_dynamics.core.monitoring.wrench import flange_wrench
from irb140_dynamics.ros.messages.wrench import chain_links
from irb140_dynamics.ros.parameters.specs import Spec
from irb140_dynamics.ros.runtime.guard import guarded
from irb140_dynamics.ros.runtime.listened import ListenedPublisher

MAX_RATE = 100.0  # Hz
LIFETIME_PERIODS = 3.0  # a marker lives this many periods (at least MIN_LIFETIME): a stopped stream's go
MIN_LIFETIME = 0.5  # s
JOINT_DIAMETER = 0.06  # m; a joint at the same place as earlier ones (SAME_PLACE) nests inside them, 0.7x each
JOINT_ALPHA = 0.6
SAME_PLACE = 0.01  # m
TEXT_HEIGHT = 0.04  # m
LABEL_RISE = 0.06  # m: a label above its sphere
WHITE, COLLISION_RED, FORCE, PAYLOAD = (1.0, 1.0, 1.0), (1.0, 0.0, 0.0), (1.0, 0.0, 1.0), (0.2, 0.4, 1.0)

MARKER_PARAMETERS = [
    Spec(
        "markers.rate",
        10.0,
        "~/markers (visualization_msgs/MarkerArray) at most this often, after new joint states; 0 = off",
        "Hz",
        minimum=0.0,
        maximum=MAX_RATE,
        read_only=True,
    ),
]


def lifetime(rate: float) -> float:
    """How long a marker lives [s] at ``rate`` [Hz]."""
    return max(LIFETIME_PERIODS / rate, MIN_LIFETIME)


def build_markers(model, limits, frame_id: str, stamp, q, tau, external=None, colliding=(), life=1.0) -> MarkerArray:
    """The markers of one joint state (see the module): ``tau`` [N m] the joint torques
    shown, ``external`` the observer's external torques (None: no efforts measured),
    ``colliding`` the names of the joints over their thresholds. ValueError if a number
    is not finite (the core's refusal, or here)."""
    markers = MarkerArray()
    new = _maker(frame_id, stamp, life)
    limits = np.full(model.n, np.inf) if limits is None else limits  # none known (yet): grey
    origins = joint_origins(model, q)
    loads = display.joint_loads(tau, limits)
    for j, (name, origin, torque, load) in enumerate(zip(model.joint_names, origins, tau, loads)):
        below = sum(float(np.linalg.norm(origins[i] - origin)) < SAME_PLACE for i in range(j))  # joints here before j
        size = JOINT_DIAMETER * 0.7**below  # nested, each seen through the one around it
        colour = display.load_colour(load)
        markers.markers.append(new("joint_load", j, Marker.SPHERE, origin, size, colour, alpha=JOINT_ALPHA))
        label = display.load_label(name, float(torque), load)
        above = origin + (0.0, 0.0, LABEL_RISE * (1 + below))  # stacked where joints share a place
        markers.markers.append(new("joint_label", j, Marker.TEXT_VIEW_FACING, above, TEXT_HEIGHT, WHITE, label))
    pose = flange_pose(model, q)
    payload = model.payload
    if payload.mass > 0.0:
        com = pose[:3, :3] @ np.asarray(payload.com, dtype=float) + pose[:3, 3]
        size = display.payload_diameter(payload.mass)
        markers.markers.append(new("payload", 0, Marker.SPHERE, com, size, PAYLOAD, alpha=0.7))
    flange = pose[:3, 3]
    if external is not None:
        force = flange_wrench(model, q, external, "base").force
        arrow = new("external_force", 0, Marker.ARROW, np.zeros(3), 0.0, FORCE)
        arrow.points = [_point(flange), _point(display.arrow_end(flange, force))]
        arrow.scale.x, arrow.scale.y, arrow.scale.z = 0.015, 0.03, 0.05  # shaft, head diameters, head length
        markers.markers.append(arrow)
        text = f"{float(np.linalg.norm(force)):.1f} N"
        where = display.arrow_end(flange, force) + (0.0, 0.0, LABEL_RISE)
        markers.markers.append(new("external_force", 1, Marker.TEXT_VIEW_FACING, where, TEXT_HEIGHT, FORCE, text))
    else:  # gone at once, not after their lifetime
        markers.markers += [_deleted(frame_id, "external_force", 0), _deleted(frame_id, "external_force", 1)]
    if colliding:
        text = "collision: " + ", ".join(colliding)
        where = flange + (0.0, 0.0, 3 * LABEL_RISE)
        markers.markers.append(
            new("collision", 0, Marker.TEXT_VIEW_FACING, where, 1.5 * TEXT_HEIGHT, COLLISION_RED, text)
        )
    else:
        markers.markers.append(_deleted(frame_id, "collision", 0))
    for marker in markers.markers:
        _check_finite(marker)
    return markers


def _deleted(frame_id: str, ns: str, id_: int) -> Marker:
    marker = Marker(ns=ns, id=id_, action=Marker.DELETE)
    marker.header.frame_id = frame_id
    return marker


def _maker(frame_id: str, stamp, life: float):
    seconds = math.floor(life)
    duration = Duration(sec=int(seconds), nanosec=int(round((life - seconds) * 1e9)) % 1_000_000_000)

    def new(ns, id_, kind, position, size, colour, text="", alpha=1.0) -> Marker:
        marker = Marker(ns=ns, id=id_, type=kind, action=Marker.ADD, text=text, lifetime=duration)
        marker.header.frame_id = frame_id
        marker.header.stamp.sec, marker.header.stamp.nanosec = stamp.sec, stamp.nanosec
        p = marker.pose.position
        p.x, p.y, p.z = (float(x) for x in position)
        marker.pose.orientation.w = 1.0
        if kind == Marker.TEXT_VIEW_FACING:
            marker.scale.z = float(size)  # a text's height
        else:
            marker.scale.x = marker.scale.y = marker.scale.z = float(size)
        c = marker.color
        c.r, c.g, c.b, c.a = (float(x) for x in (*colour, alpha))
        return marker

    return new


def _point(xyz) -> Point:
    return Point(x=float(xyz[0]), y=float(xyz[1]), z=float(xyz[2]))


def _check_finite(marker: Marker) -> None:
    p, s = marker.pose.position, marker.scale
    numbers = [p.x, p.y, p.z, s.x, s.y, s.z] + [v for point in marker.points for v in (point.x, point.y, point.z)]
    if not all(map(math.isfinite, numbers)):
        raise ValueError(f"marker {marker.ns} {marker.id} not finite")


class MarkerPublisher:
    """Keeps the last joint state's numbers (cheap, per message) and publishes their markers
    on a timer at ``rate`` [Hz] (0: never), while anything subscribes to them."""

    def __init__(self, node: Node, rate: float):
        self._node, self.tally = node, node.tally
        self._publisher = ListenedPublisher(node, MarkerArray, "~/markers", 10)
        self._rate = rate
        self._life = lifetime(rate) if rate > 0.0 else 0.0
        self._last = None  # (stamp, q, tau): the last joint state
        self._observed = None  # (external torques, colliding joint names) of the last joint state, or None
        self._fresh = False
        self.published = 0
        if rate > 0.0:
            node.create_timer(1.0 / rate, self.publish)

    def forget(self) -> None:
        """A model of other joints: the last joint state was of the one before."""
        self._last, self._observed, self._fresh = None, None, False

    def note(self, stamp, q, tau) -> None:
        """A joint state: its stamp, positions and the torques shown."""
        self._last, self._observed, self._fresh = (stamp, q, tau), None, True

    def observed(self, effort, external, colliding) -> None:
        """The joint state had efforts: those shown instead, and the external torques."""
        if self._last is not None:
            stamp, q, _ = self._last
            self._last, self._observed = (stamp, q, effort), (external, colliding)

    @guarded("markers")
    def publish(self) -> None:
        """The markers of the last joint state, if one came since the last call and a model
        is loaded (the node's settings) and anything subscribes (building markers for nobody
        would take the stream's time for nothing); none that is not finite (counted, warned)."""
        settings = getattr(self._node, "settings", None)
        if not self._fresh or settings is None or self._last is None or not self._publisher.subscribers:
            return
        self._fresh = False
        stamp, q, tau = self._last
        external, colliding = self._observed or (None, ())
        frame_id = chain_links(self._node.parameters)[0]
        try:
            markers = build_markers(
                settings.model, settings.torque_limits, frame_id, stamp, q, tau, external, colliding, self._life
            )
        except ValueError as error:
            self.tally.add("markers", "not_finite")
            self.tally.warn("markers", f"markers not published ({error})")
            return
        self._publisher.publish(markers)
        self.published += 1
