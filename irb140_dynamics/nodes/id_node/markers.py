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
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

from irb140_dynamics.core.kinematics import joint_origins_and_flange
from irb140_dynamics.core.monitoring import display
from irb140_dynamics.core.monitoring.wrench import wrench_of
from irb140_dynamics.nodes.id_node.marker_bytes import packed
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
    return MarkerScene(model, frame_id, life).update(limits, stamp, q, tau, external, colliding)


class MarkerScene:
    """The Marker messages of one model, frame and lifetime, made once (namespace, id, type,
    lifetime, alpha, a text's height); ``update`` writes one joint state's numbers into them
    (positions, sizes, colours, texts, the stamp) and returns the MarkerArray of those shown.
    The same messages serve every update: a publisher serialises them when called, so the
    stream's callbacks are not kept waiting while ~20 messages are made at each tick."""

    def __init__(self, model, frame_id: str, life: float):
        self.model, self.frame_id, self.life = model, frame_id, life
        self._header = Header(frame_id=frame_id)
        new = _maker(self._header, life)
        self._spheres = [new("joint_load", j, Marker.SPHERE, JOINT_ALPHA) for j in range(model.n)]
        self._labels = [new("joint_label", j, Marker.TEXT_VIEW_FACING, text_height=TEXT_HEIGHT) for j in range(model.n)]
        self._payload = new("payload", 0, Marker.SPHERE, 0.7, PAYLOAD) if model.payload.mass > 0.0 else None
        if self._payload is not None:
            size = float(display.payload_diameter(model.payload.mass))
            self._payload.scale.x = self._payload.scale.y = self._payload.scale.z = size
        self._payload_com = np.asarray(model.payload.com, dtype=float)
        self._arrow = new("external_force", 0, Marker.ARROW, 1.0, FORCE)
        self._arrow.scale.x, self._arrow.scale.y, self._arrow.scale.z = (
            0.015,
            0.03,
            0.05,
        )  # shaft, head diameters, head length
        self._arrow.points = [Point(), Point()]
        self._force_text = new("external_force", 1, Marker.TEXT_VIEW_FACING, 1.0, FORCE, TEXT_HEIGHT)
        self._collision = new("collision", 0, Marker.TEXT_VIEW_FACING, 1.0, COLLISION_RED, 1.5 * TEXT_HEIGHT)
        self._no_force = [_deleted(frame_id, "external_force", 0), _deleted(frame_id, "external_force", 1)]
        self._no_collision = _deleted(frame_id, "collision", 0)
        self._all_limits = np.full(model.n, np.inf)
        self._array = MarkerArray()

    def update(self, limits, stamp, q, tau, external=None, colliding=()) -> MarkerArray:
        """The markers of one joint state (see ``build_markers``); nothing is written when a
        number is not finite (ValueError)."""
        model = self.model
        origins, pose, J = joint_origins_and_flange(model, q)  # one pass of forward kinematics
        flange = pose[:3, 3]
        gap = np.linalg.norm(origins[:, None, :] - origins[None, :, :], axis=2) < SAME_PLACE
        below = np.tril(gap, -1).sum(axis=1).tolist()  # the joints at j's place before j
        sizes = [JOINT_DIAMETER * 0.7**k for k in below]  # nested, each seen through the one around it
        com = pose[:3, :3] @ self._payload_com + flange
        if external is not None:
            force = wrench_of(pose, J, external, "base").force
            end = display.arrow_end(flange, force)
            numbers = (origins, com, flange, end)
        else:
            numbers = (origins, com, flange)
        if not all(np.isfinite(x).all() for x in numbers):
            raise ValueError("markers not finite")
        loads = display.joint_loads(tau, self._all_limits if limits is None else limits)  # none known (yet): grey
        stamp_of = self._header.stamp
        stamp_of.sec, stamp_of.nanosec = stamp.sec, stamp.nanosec
        shown = []
        names, torques = model.joint_names, np.asarray(tau, dtype=float).tolist()
        for j, (x, y, z) in enumerate(origins.tolist()):
            sphere, label, load, k = self._spheres[j], self._labels[j], loads[j], below[j]
            _place(sphere, x, y, z)
            sphere.scale.x = sphere.scale.y = sphere.scale.z = sizes[j]
            _paint(sphere, display.load_colour(load))
            _place(label, x, y, z + LABEL_RISE * (1 + k))  # stacked where joints share a place
            label.text = display.load_label(names[j], torques[j], load)
            shown += (sphere, label)
        if self._payload is not None:
            _place(self._payload, *com.tolist())
            shown.append(self._payload)
        fx, fy, fz = flange.tolist()
        if external is not None:
            start, tip = self._arrow.points
            start.x, start.y, start.z = fx, fy, fz
            tip.x, tip.y, tip.z = end.tolist()
            self._force_text.text = display.force_label(force)
            ex, ey, ez = end.tolist()
            _place(self._force_text, ex, ey, ez + LABEL_RISE)
            shown += (self._arrow, self._force_text)
        else:  # gone at once, not after their lifetime
            shown += self._no_force
        if colliding:
            self._collision.text = "collision: " + ", ".join(colliding)
            _place(self._collision, fx, fy, fz + 3 * LABEL_RISE)
            shown.append(self._collision)
        else:
            shown.append(self._no_collision)
        self._array.markers = shown
        return self._array


def _deleted(frame_id: str, ns: str, id_: int) -> Marker:
    marker = Marker(ns=ns, id=id_, action=Marker.DELETE)
    marker.header.frame_id = frame_id
    return marker


def _maker(header: Header, life: float):
    seconds = math.floor(life)
    duration = Duration(sec=int(seconds), nanosec=int(round((life - seconds) * 1e9)) % 1_000_000_000)

    def new(ns, id_, kind, alpha=1.0, colour=WHITE, text_height=None) -> Marker:
        """A marker shown (ADD) in ``header``'s frame and at its stamp; its pose unturned."""
        marker = Marker(ns=ns, id=id_, type=kind, action=Marker.ADD, lifetime=duration, header=header)
        marker.pose.orientation.w = 1.0
        if text_height is not None:
            marker.scale.z = float(text_height)  # a text's height
        _paint(marker, colour)
        marker.color.a = float(alpha)
        return marker

    return new


def _place(marker: Marker, x: float, y: float, z: float) -> None:
    p = marker.pose.position
    p.x, p.y, p.z = x, y, z


def _paint(marker: Marker, colour) -> None:
    c = marker.color
    c.r, c.g, c.b = (float(x) for x in colour)


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
        self._scene = None  # the markers' messages, of the model and frame they were made for
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
        scene = self._scene
        if scene is None or scene.model is not settings.model or scene.frame_id != frame_id:
            scene = self._scene = MarkerScene(settings.model, frame_id, self._life)
        try:
            markers = scene.update(settings.torque_limits, stamp, q, tau, external, colliding)
        except ValueError as error:
            self.tally.add("markers", "not_finite")
            self.tally.warn("markers", f"markers not published ({error})")
            return
        self._publisher.publish(packed(markers))  # bytes: rclpy's field-by-field conversion skipped
        self.published += 1
