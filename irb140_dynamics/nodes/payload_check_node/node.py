"""payload_check_node: can the arm hold this payload, with what margin, how much could it hold.

Serves       ~/check        std_srvs/Trigger: the configured payload (payload.* parameters)
                            against the joint torque limits, at the current joint state (if
                            joint_states was received) and in each joint's worst static pose over the
                            joint ranges (a tree: the joints up to payload.link, the rest of the tree
                            in its worst pose); success: it fits (proven); the reply's message: a
                            one-line verdict (OK, OVER-LIMIT or UNPROVEN), then the report
             ~/estimate_payload   std_srvs/Trigger: the payload's mass and centre of mass from
                            the efforts at rest (see core.payload.rest_samples); with
                            estimation.apply, set as payload.mass and payload.com
             ~/clear_samples      std_srvs/Trigger: forget the rest samples and the last estimate
Subscribes   joint_states   sensor_msgs/JointState (matched by joint name, as in id_node)
             robot_description  std_msgs/String: the model, as in id_node (see ros.parameters.arm)
Publishes    /diagnostics   diagnostic_msgs/DiagnosticArray: one status per joint, one for the
                            payload and one for its estimate, after each check and every
                            diagnostics.period

Torque limits: <joint>.torque_limit when > 0, else as in the report the rated payload's
worst static torque over the joint ranges; none for a joint it cannot load. A joint state
older than STALE_AFTER (node clock) is still used, and the check says so. Each accepted
change (and the start, up to STARTUP_WAIT) is analysed off the executor, limits and
workspace, within check.analysis_timeout (what is not proven by then is UNPROVEN); a newer
change cancels it. ~/check waits for it, up to check.wait_timeout (see check_service).
"""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from std_srvs.srv import Trigger

from irb140_dynamics.core import gravity, rnea
from irb140_dynamics.core.model.joint_order import BadMessage, JointOrder, NotForThisModel
from irb140_dynamics.core.payload import check_payload
from irb140_dynamics.core.payload.analysis import Settings, check_settings, finish_settings
from irb140_dynamics.core.payload.rest_samples import EstimationError, PayloadEstimator
from irb140_dynamics.node_help import Usage
from irb140_dynamics.nodes.payload_check_node.check_service import CheckService, reply
from irb140_dynamics.nodes.payload_check_node.settings import NODE_PARAMETERS
from irb140_dynamics.ros.messages.joint_messages import finite_torques, read_joint_sample
from irb140_dynamics.ros.parameters.arm import DESCRIPTION_QOS, ArmParameters
from irb140_dynamics.ros.parameters.overrides import NODE_OPTIONS
from irb140_dynamics.ros.parameters.specs import joint_states_qos
from irb140_dynamics.ros.parameters.usage import model_sections
from irb140_dynamics.ros.runtime.diagnostics import payload_statuses
from irb140_dynamics.ros.runtime.guard import Tally, guarded
from irb140_dynamics.ros.runtime.rebuild import Rebuild
from irb140_dynamics.ros.runtime.spin import run

STALE_AFTER = 1.0  # s: a joint state older than this is reported as stale
STARTUP_WAIT = 2.0  # s: at most this long for the first analysis before the node is ready
NO_MODEL = "no model yet: waiting for a URDF on the robot_description topic"


def _failed(what: str):
    """A guarded service's answer to an exception of ours."""
    return lambda request, response, error: reply(
        response, False, f"{what}: internal error {type(error).__name__}: {error}"
    )


class PayloadCheckNode(Node):
    """Joint states and parameters in; ~/check, the payload estimate and /diagnostics out."""

    def __init__(self, **kwargs):
        super().__init__("payload_check_node", **NODE_OPTIONS, **kwargs)
        self.settings: Settings | None = None  # analysed; None: waiting for the model (robot_description topic)
        self.state = self.received = None  # the latest good joint state (JointSample), when received
        self._early = None  # (the latest joint state, received) before the first model
        self._started = False
        self.tally = Tally(self.get_logger())
        self.counts = self.tally.counts
        self.parameters = ArmParameters(self, NODE_PARAMETERS)
        get = self.get_parameter
        self.estimator = PayloadEstimator(get("estimation.rest_velocity").value, get("estimation.rest_time").value)
        self.check_service = CheckService(self, self._on_check, lambda: self.rebuild.pending_since is not None)
        self.rebuild = Rebuild(self, finish_settings, self._use, settled=self.check_service.settled)
        self._reader = Rebuild(self, self.parameters.read_topic, self._take_urdf)
        self._draft = None  # the settings of a change accepted by _on_set, for _on_set_done
        first = self.parameters.draft(check_settings, self.parameters.values())
        if first is not None:
            self.rebuild.submit(first)
            self.rebuild.wait(STARTUP_WAIT)  # the first analysis, if quick; else it follows
        self.add_on_set_parameters_callback(self._on_set)
        self.add_post_set_parameters_callback(self._on_set_done)
        if self.parameters.from_topic:
            self.create_subscription(String, "robot_description", self._on_description, DESCRIPTION_QOS)
        self.create_subscription(JointState, "joint_states", self._on_joint_state, joint_states_qos(self))
        self.create_service(Trigger, "~/estimate_payload", self._on_estimate)
        self.create_service(Trigger, "~/clear_samples", self._on_clear)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        if get("diagnostics.period").value > 0.0:
            self.create_timer(get("diagnostics.period").value, self._on_timer)
        self._started = True
        if self.settings is not None or self.rebuild.pending_since is not None:
            self._log_ready(first.model.payload)

    def _log_ready(self, payload) -> None:
        running = "" if self.settings is not None else " (its workspace analysis still running: ~/check waits for it)"
        self.get_logger().info(f"ready: ~/check for a {payload.mass} kg payload at {list(payload.com)} m{running}")

    @property
    def model(self):
        """The model in force (None while waiting for a URDF)."""
        return None if self.settings is None else self.settings.model

    def _on_set(self, parameters):
        """A change is accepted only if the whole new configuration checks."""
        result, self._draft = self.parameters.check_change(parameters, check_settings)
        return result

    def _on_set_done(self, parameters) -> None:
        """The change accepted: in force at once when nothing is to be analysed, else
        analysed off the executor (~/check waits for it)."""
        draft, self._draft = self._draft, None
        if draft is not None and draft.same_analysis(self.rebuild.previous):
            self.rebuild.build_here(draft)
        elif draft is not None:
            self.rebuild.submit(draft)

    def _on_description(self, msg: String) -> None:
        """A new URDF: read off the executor, then checked whole (``_take_urdf``)."""
        self._reader.submit(msg.data)

    def _take_urdf(self, urdf) -> None:
        """The URDF read: with the parameters in force analysed and swapped in, or refused."""
        draft = self.parameters.take_urdf(urdf, check_settings)
        if draft is not None:
            self.rebuild.submit(draft)

    def _use(self, settings: Settings) -> None:
        """Switch to new analysed settings; other joints forget the joint state and rest samples."""
        first, names = self.settings is None, settings.model.joint_names
        if first or names != self.settings.model.joint_names:
            self._order = JointOrder(names)
            self.state = None
            self.estimator.detector.clear()
        self.settings = settings
        self.estimator.configure(settings.rest_velocity, settings.rest_time, settings.model.friction)
        if self.state is not None:  # held: the new model must give finite torques for it too
            try:
                self._check_finite(self.state)
            except BadMessage as problem:
                self.tally.drop("joint_states", problem)
                self.state = None
        if first and self._early is not None:  # the latest joint state before the first model
            early, self._early = self._early, None
            self._take(*early)
        if first and self._started:  # the model came after startup
            self._log_ready(settings.model.payload)

    def _check_finite(self, state) -> None:
        """BadMessage unless the model gives finite torques at the state, qdd = 0 (as id_node)."""
        model = self.settings.model
        finite_torques(rnea, model, state.q, state.qd, [0.0] * model.n)
        finite_torques(gravity, model, state.q)

    @guarded("joint_states")
    def _on_joint_state(self, msg: JointState) -> None:
        self.counts["joint_states.received"] += 1
        if self.settings is None:  # the latest is kept, and taken with the first model (see _use)
            self.counts["joint_states.no_model_yet"] += 1
            self._early = (msg, self.get_clock().now())
            return
        self._take(msg, self.get_clock().now())

    def _take(self, msg: JointState, received) -> None:
        """A joint state received at ``received`` (node clock): the state checks use, and the
        payload estimate's sample; a bad one dropped, counted and warned about."""
        try:
            state = read_joint_sample(msg, self._order, lambda: received.nanoseconds * 1e-9)
            self._check_finite(state)
        except NotForThisModel:
            self.counts["joint_states.ignored"] += 1
            return
        except BadMessage as error:
            self.tally.drop("joint_states", error)
            return
        self.state, self.received = state, received
        left_out = self.estimator.take(state.t, state.q, state.qd, state.effort)
        if state.bad_effort is not None:
            left_out = f"an effort not finite, taken as none ({state.bad_effort})"
        if left_out is not None:
            self.tally.add("estimation", "effort_left_out")
            self.tally.warn("estimation", f"payload estimate: {left_out}")

    def check(self):
        """The check at the latest joint state, if any, published on /diagnostics: (the
        PayloadCheck, the state's age in words if older than STALE_AFTER, else None); (None,
        None) without a model."""
        settings, state = self.settings, self.state
        if settings is None:
            return None, None
        q, qd = (None, None) if state is None else (state.q, state.qd)
        analysis = settings.analysis
        result = check_payload(
            settings.model, settings.model.payload, analysis.limits, q, qd, workspace=analysis.workspace
        )
        age = None if state is None else (self.get_clock().now() - self.received).nanoseconds * 1e-9
        stale = f"joint_states received {age:.1f} s ago" if age is not None and age > STALE_AFTER else None
        self._publish(payload_statuses(result, self.get_name(), settings.warn_use, stale) + [self._estimate_status()])
        return result, stale

    def _not_ready(self) -> str | None:
        """None when the parameters in force are analysed; else why not (yet)."""
        if self.rebuild.failure is not None:
            return f"cannot check: {self.rebuild.status()}"
        if self.rebuild.pending_since is not None:
            return f"pending: {self.rebuild.status()} (the limits and workspace analysis); ~/check waits for it"
        return NO_MODEL if self.settings is None else None

    def _on_check(self, request, response):
        """~/check's answer now (see check_service: it waits for the analysis first)."""
        why = self._not_ready()
        if why is not None:
            return reply(response, False, f"UNPROVEN: {why}")
        result, stale = self.check()
        note = "\n(no joint_states received yet: checked over the workspace only)" if result.torque is None else ""
        return reply(response, result.ok, result.report() + note + ("" if stale is None else f"\nnote: {stale}"))

    @guarded("estimate_payload", fallback=_failed("cannot estimate"))
    def _on_estimate(self, request, response):
        """The payload from the rests so far; with estimation.apply, set as the parameters."""
        try:
            if self.settings is None:
                raise EstimationError(NO_MODEL)
            estimate, note = self.estimator.estimate(self.settings.model)
        except EstimationError as error:
            return reply(response, False, f"cannot estimate: {error}")
        message = estimate.summary() + ("" if note is None else f"\nnote: {note}")
        if not self.get_parameter("estimation.apply").value:
            return reply(response, True, message)
        mass, com = float(estimate.mass), [float(x) for x in estimate.com]  # set as any change: checked whole
        applied = self.set_parameters_atomically(
            [Parameter("payload.mass", value=mass), Parameter("payload.com", value=com)]
        )
        if applied.successful:
            return reply(response, True, f"{message}\napplied: payload.mass and payload.com set")
        return reply(response, False, f"{message}\nnot applied: {applied.reason}")

    @guarded("clear_samples", fallback=_failed("not cleared"))
    def _on_clear(self, request, response):
        return reply(response, True, self.estimator.clear())

    def _estimate_status(self) -> DiagnosticStatus:
        message, figures = self.estimator.summary()
        values = [KeyValue(key=key, value=value) for key, value in figures.items()]
        name = self.get_name()
        return DiagnosticStatus(name=f"{name}: payload estimation", hardware_id=name, message=message, values=values)

    @guarded("diagnostics")
    def _on_timer(self) -> None:
        why = self._not_ready()
        if why is None:
            self.check()
            return
        level = DiagnosticStatus.ERROR if self.rebuild.failure is not None else DiagnosticStatus.WARN
        name = self.get_name()
        self._publish([DiagnosticStatus(level=level, name=f"{name}: payload", hardware_id=name, message=why)])

    def _publish(self, statuses) -> None:
        for status in statuses:  # the robot's name (model.name, or the URDF's), as rqt_robot_monitor groups them
            status.hardware_id = self.parameters.robot_name or status.hardware_id
        diagnostics = DiagnosticArray(status=statuses)
        diagnostics.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(diagnostics)


def usage() -> Usage:
    """What ``payload_check_node --help`` prints: this module's docstring and every parameter."""
    return Usage("payload_check_node", __doc__, [*model_sections(), ("payload_check_node's own", NODE_PARAMETERS)])


def main(args=None):
    raise SystemExit(run("payload_check_node", PayloadCheckNode, args, executor="single_threaded", usage=usage))
