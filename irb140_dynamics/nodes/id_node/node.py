"""id_node: live inverse dynamics and gravity compensation.

Subscribes   joint_states          sensor_msgs/JointState (matched by joint name)
             ~/reference           trajectory_msgs/JointTrajectory: followed in time from its
                                   header.stamp (zero: on arrival; node clock) until
                                   reference_timeout after its last point; empty: let go
                                   (see core.trajectories.tracking)
             robot_description     std_msgs/String (transient local): the model, with model.source
                                   robot_description and no URDF parameter or file
                                   (see ros.parameters.arm)
Publishes    feedforward_torques   sensor_msgs/JointState, effort = tau(q, qd, qdd)
             gravity_torques       sensor_msgs/JointState, effort = g(q)
             effort_commands       std_msgs/Float64MultiArray (when enabled), model joint order:
                                   feed-forward, gravity or computed-torque commands
             ~/tracking_error      sensor_msgs/JointState while a reference is in force:
                                   position = q_ref - q, velocity = qd_ref - qd
             external_torques      sensor_msgs/JointState, effort = the external torques r of the
                                   momentum observer, for joint states that carry efforts
                                   (core.monitoring.observer)
             collision             std_msgs/Bool (reliable, transient local): true while any |r_j|
                                   exceeds joint j's collision_threshold (core.monitoring.collision)
             external_wrench       geometry_msgs/WrenchStamped (while anything subscribes): the
                                   wrench on the flange r comes from (core.monitoring.wrench), in
                                   the tip link's axes or, with external_wrench.frame base, the
                                   base link's (the torque about the flange origin in both)
             ~/markers             visualization_msgs/MarkerArray at markers.rate: loads, payload,
                                   external force, collision (see id_node.markers)
             ft_contact_wrench     WrenchStamped: ft_wrench freed of its tool; ~/estimate_ft_load (id_node.ft_sensor)
             /diagnostics          diagnostic_msgs/DiagnosticArray, 1 Hz: message counts; a
                                   collision now or since the last report (ERROR); the wrench's
                                   nearness to a singularity (WARN)

Torques are in N m, named and ordered as the model's joints, stamped with the input stamp.
A message that cannot give finite torques is dropped and counted (per topic), never
answered; no exception leaves a callback. Joint states are read, and torques published, as
serialized bytes (core.io.joint_state_cdr: a third of rclpy's cost per message).
"""

from __future__ import annotations

from array import array

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64MultiArray, String
from trajectory_msgs.msg import JointTrajectory

from irb140_dynamics.core.io.joint_state_cdr import EffortMessage
from irb140_dynamics.core.io.stamps import seconds
from irb140_dynamics.core.monitoring.collision import RESTARTS, CollisionMonitor
from irb140_dynamics.core.monitoring.wrench import WrenchStream
from irb140_dynamics.core.trajectories.stream_settings import (
    IdNodeSettings,
    check_settings,
    finish_settings,
    kernels_text,
)
from irb140_dynamics.core.trajectories.tracking import TorqueStream
from irb140_dynamics.node_help import Usage
from irb140_dynamics.nodes.id_node.ft_sensor import FtSensor
from irb140_dynamics.nodes.id_node.markers import MarkerPublisher
from irb140_dynamics.nodes.id_node.settings import NODE_PARAMETERS, PER_JOINT_PARAMETERS
from irb140_dynamics.ros.messages.joint_messages import (
    BadMessage,
    JointOrder,
    JointSample,
    NotForThisModel,
    read_joint_sample,
    read_trajectory,
)
from irb140_dynamics.ros.messages.wrench import fill_wrench
from irb140_dynamics.ros.parameters.arm import DESCRIPTION_QOS, ArmParameters
from irb140_dynamics.ros.parameters.overrides import NODE_OPTIONS
from irb140_dynamics.ros.parameters.specs import joint_states_qos
from irb140_dynamics.ros.parameters.usage import JOINT, model_sections, per_joint_section
from irb140_dynamics.ros.runtime.diagnostics import message_status
from irb140_dynamics.ros.runtime.guard import Tally, guarded
from irb140_dynamics.ros.runtime.listened import ListenedPublisher
from irb140_dynamics.ros.runtime.rebuild import Rebuild
from irb140_dynamics.ros.runtime.spin import run

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


class IdNode(Node):
    """Joint states in; feed-forward and gravity torques, commands and what efforts say out."""

    def __init__(self, **kwargs):
        super().__init__("id_node", **NODE_OPTIONS, **kwargs)
        self.settings: IdNodeSettings | None = None  # None: waiting for the model (robot_description topic)
        self._started = False
        self.tally = Tally(self.get_logger())
        self.counts = self.tally.counts
        self._reported = self.counts.copy()  # the counts at the last diagnostics
        self.stream, self.collision, self.wrench = TorqueStream(), CollisionMonitor(), WrenchStream()
        self.parameters = ArmParameters(self, NODE_PARAMETERS, PER_JOINT_PARAMETERS)
        self.rebuild = Rebuild(self, finish_settings, self._use)
        self._reader = Rebuild(self, self.parameters.read_topic, self._take_urdf)
        depth = self.get_parameter("qos.depth").value
        self._feedforward_pub = ListenedPublisher(self, JointState, "feedforward_torques", depth)
        self._gravity_pub = ListenedPublisher(self, JointState, "gravity_torques", depth)
        self._tracking_pub = ListenedPublisher(self, JointState, "~/tracking_error", depth)
        self._external_pub = ListenedPublisher(self, JointState, "external_torques", depth)
        self._wrench_pub = ListenedPublisher(self, WrenchStamped, "external_wrench", depth)
        self._collision_pub = self.create_publisher(Bool, "collision", LATCHED)
        self._collision_pub.publish(Bool(data=False))
        self._command_pub = None
        if self.get_parameter("effort_commands.enabled").value:
            self._command_pub = self.create_publisher(Float64MultiArray, "effort_commands", depth)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self._command_msg, self._wrench_msg = Float64MultiArray(), WrenchStamped()
        self.markers = MarkerPublisher(self, self.get_parameter("markers.rate").value)
        self.ft = FtSensor(self, depth)
        first = self.parameters.draft(check_settings, self.parameters.values())
        if first is not None:  # built here: a model that cannot be built stops the start (one line)
            self._use(finish_settings(first, None))
            self.rebuild.previous = self.settings
        self._draft = None  # the settings of a change accepted by _on_set, for _on_set_done
        self.add_on_set_parameters_callback(self._on_set)
        self.add_post_set_parameters_callback(self._on_set_done)
        self.create_subscription(JointState, "joint_states", self._on_joint_state, joint_states_qos(self), raw=True)
        self.create_subscription(JointTrajectory, "~/reference", self._on_reference, depth)
        if self.parameters.from_topic:
            self.create_subscription(String, "robot_description", self._on_description, DESCRIPTION_QOS)
        self.create_timer(1.0, self._publish_diagnostics)
        self._started = True
        if self.settings is not None:
            self._log_ready()

    @property
    def model(self):
        """The model in force (None while waiting for a URDF)."""
        return None if self.settings is None else self.settings.model

    def _on_set(self, parameters) -> SetParametersResult:
        """A change is accepted only if the whole new configuration checks."""
        result, self._draft = self.parameters.check_change(parameters, check_settings)
        refused = self._draft is not None and self.ft.refusal(self._draft)
        if refused:
            result, self._draft = SetParametersResult(successful=False, reason=refused), None
        return result

    def _on_set_done(self, parameters) -> None:
        """The change accepted: its settings built off the executor (kernels, limits), the
        settings before answering meanwhile."""
        draft, self._draft = self._draft, None
        if draft is not None:
            self.rebuild.submit(draft)

    def _on_description(self, msg: String) -> None:
        """A new URDF: read off the executor, then checked (``_take_urdf``)."""
        self._reader.submit(msg.data)

    def _take_urdf(self, urdf) -> None:
        """The URDF read: checked whole with the parameters in force and built off the
        executor, or refused keeping the model in use."""
        draft = self.parameters.take_urdf(urdf, check_settings)
        if draft is not None:
            self.rebuild.submit(draft)

    def _use(self, settings: IdNodeSettings) -> None:
        """New settings, built; a model of other joints starts its streams afresh."""
        old, model, names = self.settings, settings.model, list(settings.model.joint_names)
        if old is not None and self._started and model.joints != old.model.joints:
            self.get_logger().info(f"new model in force; {kernels_text(settings.kernels)}")
        if old is None or names != list(old.model.joint_names):
            self._order = JointOrder(names)
            self._feedforward_msg, self._gravity_msg = EffortMessage(names), EffortMessage(names)
            self._external_msg, self._tracking_msg = EffortMessage(names), JointState(name=names)
            self.wrench.forget()
            self.markers.forget()
        source = settings.effort_source if self._command_pub is not None else None
        mode, cutoff, timeout = settings.acceleration_mode, settings.cutoff_frequency, settings.reference_timeout
        if not self.stream.use(model, mode, cutoff, timeout, source, settings.gains):
            self.tally.drop("reference", BadMessage("non_finite_torques", "the new model gives none at the reference"))
        self.collision.use(model, settings.collision.gain, settings.collision.thresholds)
        urdf = self.parameters.urdf
        refused = self.wrench.use(settings.wrench_links, None if urdf is None else urdf.carried, not self._started)
        if refused:
            self.get_logger().error(refused)
        self.ft.use(settings, self._started)
        self.settings = settings
        if old is None and self._started:  # the model came after startup
            self._log_ready()

    def _log_ready(self) -> None:
        model = self.settings.model
        self.get_logger().info(
            f"ready: {model.n} joints {list(model.joint_names)}, payload {model.payload.mass} kg; "
            f"{kernels_text(self.settings.kernels)}"
        )

    def _now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    @guarded("joint_states")
    def _on_joint_state(self, msg: bytes | JointState) -> None:
        """A joint state as DDS carries it (see core.io.joint_state_cdr), or as a JointState."""
        self.counts["joint_states.received"] += 1
        if self.settings is None:
            self.counts["joint_states.no_model_yet"] += 1
            return
        try:
            sample = read_joint_sample(msg, self._order, self._now)
            self.ft.stream.note(sample.t, sample.q, sample.qd)
            tau, g, command, reference, terms = self.stream.torques(
                sample.t, sample.q, sample.qd, sample.effort is not None, self._now
            )
        except NotForThisModel:
            self.counts["joint_states.ignored"] += 1
            return
        except BadMessage as error:
            self.tally.drop("joint_states", error)
            return
        stamp = sample.stamp
        if self._feedforward_pub.subscribers:  # serialized for nobody would cost the stream for nothing
            self._feedforward_pub.publish(self._feedforward_msg.serialize(stamp, tau))
        if self._gravity_pub.subscribers:
            self._gravity_pub.publish(self._gravity_msg.serialize(stamp, g))
        if command is not None:
            self._command_msg.data = array("d", command)
            self._command_pub.publish(self._command_msg)
        self.counts["torques.published"] += 1
        if reference is not None and self._tracking_pub.subscribers:
            msg = self._tracking_msg
            msg.header.stamp.sec, msg.header.stamp.nanosec = stamp.sec, stamp.nanosec
            msg.position = (np.asarray(reference[0]) - sample.q).tolist()
            msg.velocity = (np.asarray(reference[1]) - sample.qd).tolist()
            self._tracking_pub.publish(msg)
        self.markers.note(stamp, sample.q, tau)
        if sample.bad_effort is not None:
            self.collision.reset()
            self.counts["collision.effort_not_finite"] += 1
            self.tally.warn("collision", f"observer skipped a joint state ({sample.bad_effort})")
        elif sample.effort is not None:
            self._observe(sample, g, terms)

    def _observe(self, sample: JointSample, g, terms) -> None:
        """Efforts measured: the external torques (external_torques), a collision, the flange
        wrench (external_wrench) and the markers of the measured efforts."""
        colliding_before = bool(self.collision.colliding)
        try:
            r = self.collision.update(sample.t, sample.q, sample.qd, sample.effort, g, terms)
        except ValueError as error:
            self.counts["collision.observer_reset"] += 1
            self.tally.warn("collision", f"observer reset ({error})")
            return
        restarted = self.collision.restarted
        if restarted is not None:
            self.counts[f"collision.restart_{restarted}"] += 1
            self.tally.warn("collision", f"observer restarted at r = 0 ({RESTARTS[restarted]})")
        if self._external_pub.subscribers:
            self._external_pub.publish(self._external_msg.serialize(sample.stamp, r))
        colliding = self.collision.colliding
        if bool(colliding) != colliding_before:
            self._collision_pub.publish(Bool(data=bool(colliding)))
        model, frame = self.settings.model, self.settings.wrench_frame
        self.markers.note(sample.stamp, sample.q, sample.effort, r, [model.joint_names[j] for j in colliding])
        self.wrench.note(model, sample.q, r)
        if not self._wrench_pub.subscribers or self.wrench.refusal:  # a tree's without links: see wrench.report()
            return
        base, tip = self.parameters.chain_links
        try:
            if self.wrench.places:  # each link's wrench in its own frame
                wrenches = [(w.link, w) for w in self.wrench.estimate_links()]
            else:
                wrenches = [(tip if frame == "tip" else base, self.wrench.estimate(frame))]
        except ValueError as error:
            self.counts["external_wrench.not_finite"] += 1
            self.tally.warn("external_wrench", f"no wrench for a joint state ({error})")
            return
        for frame_id, wrench in wrenches:
            self._wrench_pub.publish(fill_wrench(self._wrench_msg, sample.stamp, frame_id, wrench.force, wrench.torque))

    @guarded("reference")
    def _on_reference(self, msg: JointTrajectory) -> None:
        """Follow a trajectory from its header.stamp (zero: now) if the model gives finite
        torques at every point; an empty trajectory lets the reference go."""
        self.counts["reference.received"] += 1
        if not msg.points or self.settings is None:
            self.stream.tracker.clear()
            return
        try:
            start = seconds(msg.header.stamp.sec, msg.header.stamp.nanosec)
            self.stream.follow(read_trajectory(msg, self._order), start or self._now())
        except BadMessage as error:
            self.tally.drop("reference", error)

    @guarded("diagnostics")
    def _publish_diagnostics(self) -> None:
        """Message counts (see message_status), the collision and the wrench's statuses."""
        recent = self.counts - self._reported
        self._reported = self.counts.copy()
        name, hardware_id = self.get_name(), self.parameters.robot_name or self.get_fully_qualified_name()
        statuses = [
            message_status(name, hardware_id, self.counts, recent, self.rebuild, self.settings is None),
            _status(f"{name}: collision", hardware_id, self.collision.report(), DiagnosticStatus.ERROR),
            _status(f"{name}: external wrench", hardware_id, self.wrench.report(), DiagnosticStatus.WARN),
        ]
        msg = DiagnosticArray(status=statuses)
        msg.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(msg)


def _status(name: str, hardware_id: str, report, flagged_level: bytes) -> DiagnosticStatus:
    """A status of a core report (flagged, message, values): ``flagged_level`` when flagged, else OK."""
    flagged, message, values = report
    key_values = [KeyValue(key=key, value=value) for key, value in values.items()]
    level = flagged_level if flagged else DiagnosticStatus.OK
    return DiagnosticStatus(level=level, name=name, hardware_id=hardware_id, message=message, values=key_values)


def usage() -> Usage:
    """What ``id_node --help`` prints: this module's docstring and every parameter."""
    return Usage(
        "id_node",
        __doc__,
        [
            *model_sections(),
            ("id_node's own", NODE_PARAMETERS),
            per_joint_section(PER_JOINT_PARAMETERS([JOINT]), "id_node's own"),
        ],
    )


def main(args=None):
    raise SystemExit(run("id_node", IdNode, args, usage=usage))
