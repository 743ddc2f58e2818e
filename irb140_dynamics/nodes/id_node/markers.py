"""id_node's RViz markers: the joints' loads, the payload, the external force, a collision.

Publishes    ~/markers   visualization_msgs/MarkerArray, at most ``markers.rate`` Hz (0: off),
                         only after new joint states and while anything subscribes (a stopped
                         stream's markers expire after LIFETIME_PERIODS periods), in the base
                         link's frame (the URDF's name: robot_state_publisher's TF lines up)

Each marker keeps its namespace and id (RViz updates it in place); where and how large, the
colours and texts are core.monitoring.display's (``arm_picture``):

- ``joint_load`` j: a sphere at joint j's origin (nested in those of earlier joints at the
  same place, its label stacked above theirs), coloured by |tau_j| / limit_j (the measured
  effort when the joint state has efforts, else the feed-forward torque; the payload
  check's limit); ``joint_label`` j: its text, e.g. ``joint_3 81 % (85.2 N m)``;
- ``payload`` 0: a sphere at the payload's centre of mass, sized by its mass (if it has one);
- ``external_force`` 0: with efforts, the estimated force on the flange as an arrow from
  the flange origin; ``external_force`` 1 its text (N);
- ``collision`` 0: while ``collision`` is true, a red text above the flange naming the joints.

Nothing is published before a model is loaded, nor a marker that is not finite.
"""

from __future__ import annotations

import math

from builtin_interfaces.msg import Duration
from geometry_msgs.msg import Point
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

from irb140_dynamics.core.monitoring import display
from irb140_dynamics.ros.runtime.guard import guarded
from irb140_dynamics.ros.runtime.listened import ListenedPublisher

LIFETIME_PERIODS, MIN_LIFETIME = 3.0, 0.5  # a marker lives this many periods, at least MIN_LIFETIME s
JOINT_ALPHA = 0.6
TEXT_HEIGHT = 0.04  # m
LABEL_RISE = 0.06  # m: a label above its sphere
WHITE, COLLISION_RED, FORCE, PAYLOAD = (1.0, 1.0, 1.0), (1.0, 0.0, 0.0), (1.0, 0.0, 1.0), (0.2, 0.4, 1.0)


def lifetime(rate: float) -> float:
    """How long a marker lives [s] at ``rate`` [Hz]."""
    return max(LIFETIME_PERIODS / rate, MIN_LIFETIME)


def build_markers(model, limits, frame_id: str, stamp, q, tau, external=None, colliding=(), life=1.0) -> MarkerArray:
    """The markers of one joint state (see the module): ``tau`` [N m] the joint torques
    shown, ``external`` the observer's external torques (None: no efforts measured),
    ``colliding`` the names of the joints over their thresholds. ValueError if a number
    is not finite."""
    return MarkerScene(model, frame_id, life).update(limits, stamp, q, tau, external, colliding)


class MarkerScene:
    """The Marker messages of one model, frame and lifetime, made once; ``update`` writes one
    joint state's numbers into them and returns the MarkerArray of those shown (making ~20
    messages at each tick would keep the stream's callbacks waiting)."""

    def __init__(self, model, frame_id: str, life: float):
        self.model, self.frame_id = model, frame_id
        self._header = Header(frame_id=frame_id)
        seconds = math.floor(life)
        self._life = Duration(sec=int(seconds), nanosec=int(round((life - seconds) * 1e9)) % 1_000_000_000)
        new = self._new
        self._spheres = [new("joint_load", j, Marker.SPHERE, JOINT_ALPHA) for j in range(model.n)]
        self._labels = [new("joint_label", j, Marker.TEXT_VIEW_FACING, text_height=TEXT_HEIGHT) for j in range(model.n)]
        self._payload = None
        if model.payload.mass > 0.0:
            self._payload = new("payload", 0, Marker.SPHERE, 0.7, PAYLOAD)
            _size(self._payload, display.payload_diameter(model.payload.mass))
        self._arrow = new("external_force", 0, Marker.ARROW, 1.0, FORCE)
        self._arrow.scale.x, self._arrow.scale.y, self._arrow.scale.z = 0.015, 0.03, 0.05  # shaft, head, head length
        self._arrow.points = [Point(), Point()]
        self._force_text = new("external_force", 1, Marker.TEXT_VIEW_FACING, 1.0, FORCE, TEXT_HEIGHT)
        self._collision = new("collision", 0, Marker.TEXT_VIEW_FACING, 1.0, COLLISION_RED, 1.5 * TEXT_HEIGHT)
        self._no_force = [self._deleted("external_force", 0), self._deleted("external_force", 1)]
        self._no_collision = self._deleted("collision", 0)
        self._array = MarkerArray()

    def update(self, limits, stamp, q, tau, external=None, colliding=()) -> MarkerArray:
        """The markers of one joint state (see ``build_markers``); nothing is written when a
        number is not finite (ValueError)."""
        picture = display.arm_picture(self.model, q, tau, limits, external)
        self._header.stamp.sec, self._header.stamp.nanosec = stamp.sec, stamp.nanosec
        shown = []
        torques = [float(x) for x in tau]
        for j, (name, (x, y, z)) in enumerate(zip(self.model.joint_names, picture.origins)):
            sphere, label, load = self._spheres[j], self._labels[j], picture.loads[j]
            _place(sphere, x, y, z)
            _size(sphere, picture.diameters[j])
            _paint(sphere, display.load_colour(load))
            _place(label, x, y, z + LABEL_RISE * (1 + picture.earlier[j]))  # stacked where joints share a place
            label.text = display.load_label(name, torques[j], load)
            shown += (sphere, label)
        if self._payload is not None:
            _place(self._payload, *picture.payload)
            shown.append(self._payload)
        fx, fy, fz = picture.flange
        if picture.force is not None:
            start, tip = self._arrow.points
            start.x, start.y, start.z = fx, fy, fz
            tip.x, tip.y, tip.z = picture.arrow_end
            self._force_text.text = display.force_label(picture.force)
            ex, ey, ez = picture.arrow_end
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

    def _new(self, ns, id_, kind, alpha=1.0, colour=WHITE, text_height=None) -> Marker:
        """A marker shown (ADD) in the scene's frame, at its stamp, for its lifetime; its pose unturned."""
        marker = Marker(ns=ns, id=id_, type=kind, action=Marker.ADD, lifetime=self._life, header=self._header)
        marker.pose.orientation.w = 1.0
        if text_height is not None:
            marker.scale.z = float(text_height)
        _paint(marker, colour)
        marker.color.a = float(alpha)
        return marker

    def _deleted(self, ns: str, id_: int) -> Marker:
        marker = Marker(ns=ns, id=id_, action=Marker.DELETE)
        marker.header.frame_id = self.frame_id
        return marker


def _place(marker: Marker, x: float, y: float, z: float) -> None:
    p = marker.pose.position
    p.x, p.y, p.z = x, y, z


def _size(marker: Marker, diameter: float) -> None:
    marker.scale.x = marker.scale.y = marker.scale.z = float(diameter)


def _paint(marker: Marker, colour) -> None:
    c = marker.color
    c.r, c.g, c.b = (float(x) for x in colour)


class MarkerPublisher:
    """Keeps the last joint state's numbers (cheap, per message) and publishes their markers
    on a timer at ``rate`` [Hz] (0: never), while anything subscribes."""

    def __init__(self, node, rate: float):
        self._node, self.tally = node, node.tally
        self._publisher = ListenedPublisher(node, MarkerArray, "~/markers", 10)
        self._life = lifetime(rate) if rate > 0.0 else 0.0
        self._scene = None  # the markers' messages, of the model and frame they were made for
        self.published = 0
        self.forget()
        if rate > 0.0:
            node.create_timer(1.0 / rate, self.publish)

    def forget(self) -> None:
        """A model of other joints: the last joint state was of the one before."""
        self._last, self._fresh = None, False

    def note(self, stamp, q, tau, external=None, colliding=()) -> None:
        """A joint state: its stamp, positions, the torques shown and, with efforts, the
        observer's external torques and the names of the joints colliding."""
        self._last, self._fresh = (stamp, q, tau, external, colliding), True

    @guarded("markers")
    def publish(self) -> None:
        """The markers of the last joint state, if one came since the last call, a model is
        loaded and anything subscribes; none that is not finite (counted, warned)."""
        settings = self._node.settings
        if not self._fresh or settings is None or self._last is None or not self._publisher.subscribers:
            return
        self._fresh = False
        frame_id = self._node.parameters.chain_links[0]
        scene = self._scene
        if scene is None or scene.model is not settings.model or scene.frame_id != frame_id:
            scene = self._scene = MarkerScene(settings.model, frame_id, self._life)
        try:
            markers = scene.update(settings.torque_limits, *self._last)
        except ValueError as error:
            self.tally.add("markers", "not_finite")
            self.tally.warn("markers", f"markers not published ({error})")
            return
        self._publisher.publish(markers)
        self.published += 1
