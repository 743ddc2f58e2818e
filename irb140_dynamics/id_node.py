"""id_node: live inverse dynamics and gravity compensation.

Subscribes   joint_states          sensor_msgs/JointState (matched by joint name)
             ~/reference           trajectory_msgs/JointTrajectory (first point: exact feed-forward)
Publishes    feedforward_torques   sensor_msgs/JointState, effort = tau(q, qd, qdd)
             gravity_torques       sensor_msgs/JointState, effort = g(q)
             effort_commands       std_msgs/Float64MultiArray (when enabled), model joint order
             /diagnostics          diagnostic_msgs/DiagnosticArray, message counts, 1 Hz
             (an empty ~/reference trajectory lets the held reference go)

Torques are in N m, named and ordered as the model's joints, stamped with the input stamp.
A message that cannot give finite torques is dropped and counted (per topic), never
answered; no exception leaves a callback.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from .core import RobotModel, gravity, rnea
from .core.filters import VelocityDifferentiator
from .ros.guard import Tally, guarded
from .ros.messages import (
    BadMessage,
    JointOrder,
    NotForThisModel,
    finite_torques,
    joint_efforts,
    read_joint_state,
    read_reference,
)
from .ros.node_parameters import (
    ACCELERATION_MODES,
    EFFORT_SOURCES,
    ID_NODE,
    MAX_CUTOFF_FREQUENCY,
    MAX_DURATION,
)
from .ros.params import check_choice, check_number, check_qos, declare_model, joint_states_qos
from .ros.spin import run


@dataclass(frozen=True)
class Settings:
    """What the node runs on, validated from all of its parameters at once."""

    model: RobotModel
    acceleration_mode: str
    cutoff_frequency: float
    reference_timeout: float
    effort_source: str


def check_settings(values: dict) -> Settings:
    """Validate every parameter (quick, within the parameter call); kernels not compiled yet."""
    model = RobotModel.from_params(values)
    check_choice("acceleration.mode", values["acceleration.mode"], ACCELERATION_MODES)
    check_choice("effort_commands.source", values["effort_commands.source"], EFFORT_SOURCES)
    check_qos(values)
    return Settings(
        model,
        values["acceleration.mode"],
        check_number("acceleration.cutoff_frequency", values["acceleration.cutoff_frequency"], 1e-3,
                     MAX_CUTOFF_FREQUENCY, "Hz"),
        check_number("reference_timeout", values["reference_timeout"], 0.0, MAX_DURATION, "s"),
        values["effort_commands.source"],
    )


KERNELS = ("rnea", "gravity_torques")  # what a message uses


def finish_settings(settings: Settings, previous: Settings | None) -> Settings:
    """Compile the kernels the messages use, here and not on a message (off the executor
    unless they exist already: a payload or gravity change shares the arm's code)."""
    if previous is not None and previous.model == settings.model:
        return replace(settings, model=previous.model)
    _compiled = [getattr(settings.model.kernels, name) for name in KERNELS]
    return settings


def compiled(settings: Settings, previous: Settings | None) -> bool:
    return settings.model.kernels.compiled(*KERNELS)


class IdNode(Node):
    """Joint states in; feed-forward and gravity torques out."""

    def __init__(self, **kwargs):
        super().__init__("id_node", **kwargs)
        self.tally = Tally(self.get_logger())
        self.counts = self.tally.counts
        self._reported = self.counts.copy()  # the counts at the last diagnostics
        self._reference = None  # (time received [ns, node clock], q, qd, qdd or None)
        self._differentiator = None
        self.settings: Settings | None = None
        self.parameters = declare_model(self, ID_NODE, check_settings, finish_settings, quick=compiled)
        self._use(self.parameters.current)
        self.parameters.on_change(self._use)

        names = list(self.settings.model.joint_names)
        self._order = JointOrder(names)
        self._zeros = [0.0] * len(names)
        self._feedforward_msg = JointState(name=names)
        self._gravity_msg = JointState(name=names)
        self._command_msg = Float64MultiArray()

        depth = self.get_parameter("qos.depth").value
        self.create_subscription(JointState, "joint_states", self._on_joint_state, joint_states_qos(self))
        self.create_subscription(JointTrajectory, "~/reference", self._on_reference, depth)
        self._feedforward_pub = self.create_publisher(JointState, "feedforward_torques", depth)
        self._gravity_pub = self.create_publisher(JointState, "gravity_torques", depth)
        self._command_pub = None
        if self.get_parameter("effort_commands.enabled").value:
            self._command_pub = self.create_publisher(Float64MultiArray, "effort_commands", depth)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self.create_timer(1.0, self._publish_diagnostics)
        self.get_logger().info(
            f"ready: {len(names)} joints {names}, payload {self.settings.model.payload.mass} kg"
        )

    def _use(self, settings: Settings) -> None:
        """Switch to new (validated, compiled) settings; a held reference they cannot give
        finite torques for is let go."""
        if self.settings is None or settings.cutoff_frequency != self.settings.cutoff_frequency:
            self._differentiator = VelocityDifferentiator(settings.model.n, settings.cutoff_frequency)
        self.settings = settings
        if self._reference is not None:
            _, q, qd, qdd = self._reference
            try:
                finite_torques(rnea, settings.model, q, qd, [0.0] * settings.model.n if qdd is None else qdd)
            except BadMessage as error:
                self._reference = None
                self.tally.drop("reference", error)

    @guarded("joint_states")
    def _on_joint_state(self, msg: JointState) -> None:
        self.counts["joint_states.received"] += 1
        settings = self.settings
        try:
            q, qd = read_joint_state(msg, self._order)
            torques = self._torques(msg, q, qd, settings)
        except NotForThisModel:
            self.counts["joint_states.ignored"] += 1
            return
        except BadMessage as error:
            self.tally.drop("joint_states", error)
            return
        tau, g, command = torques
        stamp = msg.header.stamp
        self._feedforward_pub.publish(joint_efforts(self._feedforward_msg, stamp, tau))
        self._gravity_pub.publish(joint_efforts(self._gravity_msg, stamp, g))
        if self._command_pub is not None:
            self._command_msg.data = command.tolist()
            self._command_pub.publish(self._command_msg)
        self.counts["torques.published"] += 1

    def _torques(self, msg: JointState, q, qd, settings: Settings):
        """(feed-forward, gravity, command torques or None), all finite, or BadMessage."""
        model = settings.model
        estimate = self._estimated_acceleration(msg, qd, settings)
        q_ff, qd_ff, qdd_ref = self._fresh_reference(settings) or (q, qd, None)
        try:
            tau = finite_torques(rnea, model, q_ff, qd_ff, estimate if qdd_ref is None else qdd_ref)
            g = finite_torques(gravity, model, q)
            command = None
            if self._command_pub is not None:
                if settings.effort_source == "gravity":
                    command = g
                elif qdd_ref is None and settings.acceleration_mode == "differentiate":
                    command = finite_torques(rnea, model, q_ff, qd_ff, self._zeros)  # never a measured qdd
                else:
                    command = tau
        except BadMessage:
            if settings.acceleration_mode == "differentiate":
                self._differentiator.reset()  # the estimate may be what overflowed: start afresh
            raise
        return tau, g, command

    def _estimated_acceleration(self, msg: JointState, qd, settings: Settings):
        if settings.acceleration_mode == "zero":
            return self._zeros
        stamp = msg.header.stamp
        t = stamp.sec + 1e-9 * stamp.nanosec
        if t == 0.0:  # an unstamped stream: time of arrival
            t = self.get_clock().now().nanoseconds * 1e-9
        qdd = self._differentiator.update(t, qd)
        if not all(map(math.isfinite, qdd)):  # an absurd velocity jump overflowed the difference
            self._differentiator.reset()
            raise BadMessage("not_finite_acceleration", f"the differentiated velocities give {qdd}")
        return qdd

    @guarded("reference")
    def _on_reference(self, msg: JointTrajectory) -> None:
        """Hold the first point of a trajectory if the model gives finite torques there;
        an empty trajectory lets the reference go."""
        self.counts["reference.received"] += 1
        if not msg.points:
            self._reference = None
            return
        try:
            q, qd, qdd = read_reference(msg, self._order)
            finite_torques(rnea, self.settings.model, q, qd, self._zeros if qdd is None else qdd)
        except BadMessage as error:
            self.tally.drop("reference", error)
            return
        self._reference = (self.get_clock().now().nanoseconds, q, qd, qdd)

    def _fresh_reference(self, settings: Settings):
        if self._reference is None:
            return None
        received, q, qd, qdd = self._reference
        timeout = settings.reference_timeout
        if timeout > 0.0 and (self.get_clock().now().nanoseconds - received) * 1e-9 > timeout:
            return None
        return q, qd, qdd

    @guarded("diagnostics")
    def _publish_diagnostics(self) -> None:
        """Message counts; WARN while messages are dropped or joint_states stop coming,
        ERROR when accepted parameters could not be applied."""
        recent = self.counts - self._reported
        self._reported = self.counts.copy()
        status = DiagnosticStatus(name=f"{self.get_name()}: messages", hardware_id=self.get_fully_qualified_name())
        dropped = sum(n for key, n in recent.items() if key.endswith((".dropped", ".errors")))
        parameters = self.parameters.status()
        if self.parameters.failure is not None:
            status.level, status.message = DiagnosticStatus.ERROR, parameters
        elif dropped:
            status.level = DiagnosticStatus.WARN
            status.message = f"{dropped} messages dropped in the last second"
        elif self.counts["joint_states.received"] and not recent["joint_states.received"]:
            status.level = DiagnosticStatus.WARN
            status.message = "no joint_states in the last second"
        else:
            status.level = DiagnosticStatus.OK
            status.message = f"{recent['torques.published']} torque messages in the last second"
        values = [KeyValue(key=key, value=str(value)) for key, value in sorted(self.counts.items())]
        values.append(KeyValue(key="parameters", value=parameters or "in force"))
        status.values = values
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(msg)


def main(args=None):
    raise SystemExit(run("id_node", IdNode, args))


if __name__ == "__main__":
    main()
