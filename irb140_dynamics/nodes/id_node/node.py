"""id_node: live inverse dynamics and gravity compensation.

Subscribes   joint_states          sensor_msgs/JointState (matched by joint name)
             ~/reference           trajectory_msgs/JointTrajectory: followed in time from its
                                   header.stamp, or on arrival (see nodes.id_node.tracking)
             robot_description     std_msgs/String (transient local): the model, with model.source
                                   robot_description and no URDF parameter or file
                                   (see ros.parameters.model_source)
Publishes    feedforward_torques   sensor_msgs/JointState, effort = tau(q, qd, qdd)
             gravity_torques       sensor_msgs/JointState, effort = g(q)
             effort_commands       std_msgs/Float64MultiArray (when enabled), model joint order:
                                   feed-forward, gravity or computed-torque commands
             ~/tracking_error      sensor_msgs/JointState, position = q_ref - q, velocity = qd_ref - qd
             external_torques      sensor_msgs/JointState, effort = external torques by the momentum
                                   observer (for joint states that carry efforts;
                                   see nodes.id_node.collision)
             collision             std_msgs/Bool (transient local), any over its collision_threshold
             external_wrench       geometry_msgs/WrenchStamped: the wrench on the flange the external
                                   torques come from (see id_node.wrench)
             ~/markers             visualization_msgs/MarkerArray at markers.rate: loads, payload,
                                   external force, collision (see id_node.markers)
             /diagnostics          diagnostic_msgs/DiagnosticArray, message counts and collision, 1 Hz
             (an empty ~/reference trajectory lets the held reference go)

Torques are in N m, named and ordered as the model's joints, stamped with the input stamp.
A message that cannot give finite torques is dropped and counted (per topic), never
answered; no exception leaves a callback. Joint states are read, and torques published, as
serialized bytes (ros.messages.joint_state_cdr: a third of rclpy's cost per message).
"""

from __future__ import annotations

import math
from array import array

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from irb140_dynamics.core import RobotModel, gravity, rnea
from irb140_dynamics.core.io.stamps import seconds
from irb140_dynamics.core.monitoring.filters import VelocityDifferentiator
from irb140_dynamics.core.monitoring.observer import monitor_terms
from irb140_dynamics.nodes.id_node.collision import RESTARTS, CollisionMonitor
from irb140_dynamics.nodes.id_node.markers import MarkerPublisher
from irb140_dynamics.nodes.id_node.settings import (  # noqa: F401 (finish_settings, compiled: looked up here, tests patch them)
    NODE_PARAMETERS,
    PER_JOINT_PARAMETERS,
    IdNodeSettings,
    check_settings,
    compiled,
    finish_settings,
    kernels_text,
)
from irb140_dynamics.nodes.id_node.tracking import ReferenceTracker
from irb140_dynamics.nodes.id_node.wrench import WrenchSensor
from irb140_dynamics.ros.messages.joint_messages import (
    BadMessage,
    JointOrder,
    NotForThisModel,
    core_result,
    finite_torques,
    publish_efforts,
    read_effort,
    read_joint_state,
    read_trajectory,
)
from irb140_dynamics.ros.messages.joint_state_cdr import EffortMessage, read_joint_state_cdr
from irb140_dynamics.ros.messages.wrench import chain_links
from irb140_dynamics.ros.parameters.live import Recipe
from irb140_dynamics.ros.parameters.model_source import declare_model_source
from irb140_dynamics.ros.parameters.overrides import NODE_OPTIONS
from irb140_dynamics.ros.parameters.specs import joint_states_qos
from irb140_dynamics.ros.parameters.usage import JOINT, model_sections, per_joint_section
from irb140_dynamics.ros.runtime.command_line import Usage
from irb140_dynamics.ros.runtime.diagnostics import message_status
from irb140_dynamics.ros.runtime.guard import Tally, guarded
from irb140_dynamics.ros.runtime.listened import ListenedPublisher
from irb140_dynamics.ros.runtime.spin import run


class IdNode(Node):
    """Joint states in; feed-forward and gravity torques out."""

    def __init__(self, **kwargs):
        super().__init__("id_node", **NODE_OPTIONS, **kwargs)
        self.settings: IdNodeSettings | None = None  # None: waiting for the model (robot_description topic)
        self._started = False
        self.tally = Tally(self.get_logger())
        self.counts = self.tally.counts
        self._reported = self.counts.copy()  # the counts at the last diagnostics
        self.tracker = ReferenceTracker()
        self._differentiator = None
        recipe = Recipe(NODE_PARAMETERS, check_settings, PER_JOINT_PARAMETERS, finish=finish_settings, quick=compiled)
        self.parameters = declare_model_source(self, recipe)
        self.parameters.on_change(self._use)
        self.collision = CollisionMonitor(self, [], self.get_parameter("qos.depth").value)  # joints: by _use
        self.wrench = WrenchSensor(self, self.get_parameter("qos.depth").value)
        self.markers = MarkerPublisher(self, self.get_parameter("markers.rate").value)
        self._command_msg = Float64MultiArray()
        if self.parameters.current is not None:
            self._use(self.parameters.current)

        depth = self.get_parameter("qos.depth").value
        self.create_subscription(JointState, "joint_states", self._on_joint_state, joint_states_qos(self), raw=True)
        self.create_subscription(JointTrajectory, "~/reference", self._on_reference, depth)
        self._feedforward_pub = ListenedPublisher(self, JointState, "feedforward_torques", depth)
        self._gravity_pub = ListenedPublisher(self, JointState, "gravity_torques", depth)
        self._tracking_pub = ListenedPublisher(self, JointState, "~/tracking_error", depth)
        self._command_pub = None
        if self.get_parameter("effort_commands.enabled").value:
            self._command_pub = self.create_publisher(Float64MultiArray, "effort_commands", depth)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self.create_timer(1.0, self._publish_diagnostics)
        self._started = True
        if self.settings is not None:
            self._log_ready()

    @property
    def model(self) -> RobotModel | None:
        """The RobotModel in force; None while waiting for a URDF."""
        return None if self.settings is None else self.settings.model

    def _use(self, settings: IdNodeSettings) -> None:
        """Switch to new (validated, compiled) settings; new joints come with a new model. A
        held reference the new model gives no finite torques for is let go."""
        first, names = self.settings is None, list(settings.model.joint_names)
        if not first and self._started and settings.kernels is not self.settings.kernels:
            self.get_logger().info(f"new model in force; {kernels_text(settings.kernels)}")
        if first or names != list(self.settings.model.joint_names):
            self._order = JointOrder(names)
            self._zeros = np.zeros(len(names))
            self._feedforward_msg = EffortMessage(names)
            self._gravity_msg = EffortMessage(names)
            self._tracking_msg = JointState(name=names)
            self.tracker.clear()
            self._differentiator = None
            self.wrench.forget()
            self.markers.forget()
        if self._differentiator is None or settings.cutoff_frequency != self.settings.cutoff_frequency:
            self._differentiator = VelocityDifferentiator(settings.model.n, settings.cutoff_frequency)
        self.collision.use(settings.model, settings.collision)
        self.settings = settings
        held = self.tracker.trajectory
        if held is not None and not held.torques_finite(settings.model):
            self.tracker.clear()
            self.tally.drop("reference", BadMessage("non_finite_torques", "the new model gives none at the reference"))
        if first and self._started:  # the model came after startup
            self._log_ready()

    def _log_ready(self) -> None:
        names = list(self.settings.model.joint_names)
        self.get_logger().info(
            f"ready: {len(names)} joints {names}, payload {self.settings.model.payload.mass} kg; "
            f"{kernels_text(self.settings.kernels)}"
        )

    @guarded("joint_states")
    def _on_joint_state(self, msg: bytes | JointState) -> None:
        """A joint state as DDS carries it (see ros.messages.joint_state_cdr), or as a JointState."""
        self.counts["joint_states.received"] += 1
        settings = self.settings
        if settings is None:
            self.counts["joint_states.no_model_yet"] += 1
            return
        try:
            if isinstance(msg, bytes):
                msg = read_joint_state_cdr(msg)
            q, qd = read_joint_state(msg, self._order)
            q, qd = np.array(q), np.array(qd)  # float64 arrays: what the native kernels take
            t = self._time_of(msg)
            tau, g, command, reference, terms = self._torques(msg, t, q, qd, settings)
        except NotForThisModel:
            self.counts["joint_states.ignored"] += 1
            return
        except BadMessage as error:
            self.tally.drop("joint_states", error)
            return
        stamp = msg.header.stamp
        publish_efforts(self._feedforward_pub, self._feedforward_msg, stamp, tau)
        publish_efforts(self._gravity_pub, self._gravity_msg, stamp, g)
        if command is not None:
            self._command_msg.data = array("d", command)
            self._command_pub.publish(self._command_msg)
        self.counts["torques.published"] += 1
        if reference is not None and self._tracking_pub.subscribers:
            self._publish_tracking_error(stamp, q, qd, reference)
        self.markers.note(stamp, q, tau)
        self._observe(msg, t, q, qd, g, terms)

    def _publish_tracking_error(self, stamp, q, qd, reference) -> None:
        q_ref, qd_ref, _ = reference
        msg = self._tracking_msg
        msg.header.stamp.sec, msg.header.stamp.nanosec = stamp.sec, stamp.nanosec
        msg.position = (np.asarray(q_ref) - q).tolist()
        msg.velocity = (np.asarray(qd_ref) - qd).tolist()
        self._tracking_pub.publish(msg)

    def _torques(self, msg, t: float, q, qd, settings: IdNodeSettings):
        """(feed-forward, gravity, command torques or None, the reference in force or None,
        the observer's terms or None), the torques all finite, or BadMessage. With efforts
        and no reference, one pass gives the torques and the observer's terms."""
        model = settings.model
        estimate = self._estimated_acceleration(t, qd, settings)
        tracker = self.tracker
        reference = (
            tracker.sample(self.get_clock().now().nanoseconds * 1e-9, settings.reference_timeout)
            if tracker.trajectory is not None
            else None
        )  # no clock read without one
        q_ff, qd_ff, qdd_ref = reference or (q, qd, None)
        try:
            terms = None
            if reference is None and len(msg.effort):
                tau, g, *terms = core_result(monitor_terms, model, q, qd, estimate)  # refuses non-finite tau, g
            else:
                tau = finite_torques(rnea, model, q_ff, qd_ff, estimate if qdd_ref is None else qdd_ref)
                g = finite_torques(gravity, model, q)
            command = None
            if self._command_pub is not None:
                if settings.effort_source == "gravity":
                    command = g
                elif settings.effort_source == "computed_torque":
                    command = finite_torques(self.tracker.command, model, q, qd, reference, settings.gains)
                elif qdd_ref is None and settings.acceleration_mode == "differentiate":
                    command = finite_torques(rnea, model, q_ff, qd_ff, self._zeros)  # never a measured qdd
                else:
                    command = tau
        except BadMessage:
            if settings.acceleration_mode == "differentiate":
                self._differentiator.reset()  # the estimate may be what overflowed: start afresh
            raise
        return tau, g, command, reference, terms

    def _observe(self, msg, t: float, q, qd, g, terms) -> None:
        """Efforts in the message: run the momentum observer (external torques, collision),
        counting its restarts (collision.restart_gap, _repeated_stamp, _older_stamp)."""
        try:
            effort = read_effort(msg, self._order)
        except BadMessage as error:
            self.collision.reset()
            self.counts[f"collision.{error.kind}"] += 1
            self.tally.warn("collision", f"observer skipped a joint state ({error})")
            return
        if effort is None:
            return
        try:
            restarted = self.collision.update(t, q, qd, effort, g, msg.header.stamp, terms)
        except ValueError as error:
            self.counts["collision.observer_reset"] += 1
            self.tally.warn("collision", f"observer reset ({error})")
            return
        if restarted is not None:
            self.counts[f"collision.restart_{restarted}"] += 1
            self.tally.warn("collision", f"observer restarted at r = 0 ({RESTARTS[restarted]})")
        self._estimate_wrench(msg.header.stamp, q, effort)

    def _estimate_wrench(self, stamp, q, effort) -> None:
        """The observer's external torques as the flange wrench (external_wrench) and markers."""
        settings, r = self.settings, self.collision.residual
        colliding = [settings.model.joint_names[j] for j in self.collision.colliding]
        self.markers.observed(effort, r, colliding)
        try:
            self.wrench.update(settings.model, settings.wrench_frame, chain_links(self.parameters), stamp, q, r)
        except ValueError as error:
            self.counts["external_wrench.not_finite"] += 1
            self.tally.warn("external_wrench", f"no wrench for a joint state ({error})")

    def _estimated_acceleration(self, t: float, qd, settings: IdNodeSettings):
        if settings.acceleration_mode == "zero":
            return self._zeros
        qdd = self._differentiator.update(t, qd.tolist())  # Python floats: an overflow is inf, no warning
        if not all(map(math.isfinite, qdd)):  # an absurd velocity jump overflowed the difference
            self._differentiator.reset()
            raise BadMessage("not_finite_acceleration", f"the differentiated velocities give {qdd}")
        return np.array(qdd)

    def _time_of(self, msg) -> float:
        """The message's stamp [s]; for an unstamped stream, the time of arrival."""
        stamp = msg.header.stamp
        t = seconds(stamp.sec, stamp.nanosec)
        return t if t != 0.0 else self.get_clock().now().nanoseconds * 1e-9

    @guarded("reference")
    def _on_reference(self, msg: JointTrajectory) -> None:
        """Follow a trajectory from its header.stamp (zero: now) if the model gives finite
        torques at every point; an empty trajectory lets the reference go."""
        self.counts["reference.received"] += 1
        if not msg.points or self.settings is None:
            self.tracker.clear()
            return
        try:
            trajectory = read_trajectory(msg, self._order)
            if not trajectory.torques_finite(self.settings.model):
                raise BadMessage("non_finite_torques", "the model gives no finite torques at some point")
        except BadMessage as error:
            self.tally.drop("reference", error)
            return
        start = seconds(msg.header.stamp.sec, msg.header.stamp.nanosec)
        self.tracker.follow(trajectory, start or self.get_clock().now().nanoseconds * 1e-9)

    @guarded("diagnostics")
    def _publish_diagnostics(self) -> None:
        """Message counts (see message_status) and the collision status."""
        recent = self.counts - self._reported
        self._reported = self.counts.copy()
        name, hardware_id = self.get_name(), self.parameters.robot_name or self.get_fully_qualified_name()
        status = message_status(name, hardware_id, self.counts, recent, self.parameters, self.settings is None)
        statuses = [status, self.collision.status(name, hardware_id), self.wrench.status(name, hardware_id)]
        msg = DiagnosticArray(status=statuses)
        msg.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(msg)


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


if __name__ == "__main__":
    main()
