"""payload_check_node: can the arm hold this payload, with what margin, how much could it hold.

Serves       ~/check        std_srvs/Trigger: the configured payload (payload.* parameters)
                            against the joint torque limits, at the current joint state (if
                            joint_states was received) and in each joint's worst static pose
                            over the joint ranges; success: it fits (proven); the reply's
                            message: a one-line verdict (OK, OVER-LIMIT or UNPROVEN), then
                            the report
             ~/estimate_payload, ~/clear_samples   std_srvs/Trigger: payload estimation from the
                            efforts at rest (see nodes/payload_check_node/payload_estimator.py)
Subscribes   joint_states   sensor_msgs/JointState (matched by joint name, as in id_node)
             robot_description  std_msgs/String: the model, as in id_node (see ros.parameters.model_source)
Publishes    /diagnostics   diagnostic_msgs/DiagnosticArray: one status per joint and one for
                            the payload, after each check and every diagnostics.period

Torque limits: <joint>.torque_limit when > 0, else derived as in the report: the worst
static torque of the rated payload over the joint ranges; none for a joint it cannot load.
A joint state older than STALE_AFTER (node clock) is still used, and the check says so.
The limits and the workspace analysis are computed off the executor after each accepted
change (and at startup, up to STARTUP_WAIT before the node comes up), within
check.analysis_timeout (what is not proven by then is UNPROVEN); a newer change cancels
the analysis under way. Until they are done, ~/check waits for them, up to
check.wait_timeout (see check_service).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.node import Node
from sensor_msgs.msg import JointState

from irb140_dynamics.core import RigidBody, RobotModel, gravity, rnea
from irb140_dynamics.core.io.stamps import seconds
from irb140_dynamics.core.payload import (
    TorqueLimits,
    WorkspaceLoad,
    check_payload,
    derive_torque_limits,
    workspace_load,
)
from irb140_dynamics.core.payload.mass_com_estimation import EstimationError
from irb140_dynamics.core.payload.stop import stopping
from irb140_dynamics.nodes.payload_check_node.check_service import CheckService
from irb140_dynamics.nodes.payload_check_node.payload_estimator import ESTIMATION_PARAMETERS, PayloadEstimator
from irb140_dynamics.ros.messages.joint_messages import (
    BadMessage,
    JointOrder,
    NotForThisModel,
    finite_torques,
    read_effort,
    read_joint_state,
)
from irb140_dynamics.ros.parameters.live import Recipe
from irb140_dynamics.ros.parameters.model_source import declare_model_source
from irb140_dynamics.ros.parameters.overrides import NODE_OPTIONS
from irb140_dynamics.ros.parameters.specs import (
    MAX_MASS,
    QOS_PARAMETERS,
    RELIABILITIES,
    Spec,
    check_choice,
    joint_states_qos,
)
from irb140_dynamics.ros.parameters.usage import model_sections
from irb140_dynamics.ros.runtime.command_line import Usage
from irb140_dynamics.ros.runtime.diagnostics import payload_statuses
from irb140_dynamics.ros.runtime.guard import Tally, guarded
from irb140_dynamics.ros.runtime.spin import run

MIN_DIAGNOSTICS_PERIOD, MAX_DIAGNOSTICS_PERIOD = 0.1, 3600.0  # s
MAX_WARN_USE = 1e6  # %
MIN_ANALYSIS_TIME, MAX_ANALYSIS_TIME = 0.1, 3600.0  # s: check.analysis_timeout
MAX_WAIT = 600.0  # s: check.wait_timeout
NODE_PARAMETERS = [
    Spec(
        "rated_payload.mass",
        6.0,
        "the rated payload the torque limits are derived from",
        "kg",
        minimum=0.0,
        maximum=MAX_MASS,
    ),
    Spec("rated_payload.com", [0.0, 0.0, 0.0], "its centre of mass, in the flange frame", "m"),
    Spec(
        "diagnostics.warn_use",
        90.0,
        "a joint using more of its limit than this is a WARN",
        "%",
        minimum=0.0,
        maximum=MAX_WARN_USE,
    ),
    Spec(
        "diagnostics.period",
        1.0,
        f"check and publish /diagnostics this often, {MIN_DIAGNOSTICS_PERIOD:g} to {MAX_DIAGNOSTICS_PERIOD:g}; "
        "0 = only on ~/check",
        "s",
        minimum=0.0,
        maximum=MAX_DIAGNOSTICS_PERIOD,
        read_only=True,
    ),
    Spec(
        "check.analysis_timeout",
        20.0,
        f"the analysis of new parameters (limits, workspace) stops after this long, {MIN_ANALYSIS_TIME:g} to "
        f"{MAX_ANALYSIS_TIME:g}; what it has not proven by then ~/check answers UNPROVEN",
        "s",
        minimum=MIN_ANALYSIS_TIME,
        maximum=MAX_ANALYSIS_TIME,
        read_only=True,
    ),
    Spec(
        "check.wait_timeout",
        30.0,
        f"~/check waits this long for the analysis of new parameters in progress, 0 to {MAX_WAIT:g}; "
        "after it answers UNPROVEN (still running)",
        "s",
        minimum=0.0,
        maximum=MAX_WAIT,
    ),
    *ESTIMATION_PARAMETERS,
    *QOS_PARAMETERS,
]
STALE_AFTER = 1.0  # s: a joint state older than this is reported as stale
STARTUP_WAIT = 2.0  # s: at most this long for the first analysis before the node is ready


@dataclass(frozen=True)
class Draft:
    """The validated parameters a check depends on, before the analysis."""

    model: RobotModel  # with the payload under test
    rated_payload: RigidBody
    warn_use: float
    rest_velocity: float  # rad/s, payload estimation
    rest_time: float  # s
    analysis_timeout: float = MAX_ANALYSIS_TIME  # s


@dataclass(frozen=True)
class PayloadCheckSettings:
    """What a check needs that depends only on the parameters, the workspace sweep included."""

    model: RobotModel  # with the payload under test
    rated_payload: RigidBody
    warn_use: float
    limits: TorqueLimits
    workspace: WorkspaceLoad  # the payload's worst static loads and largest mass
    rest_velocity: float  # rad/s, payload estimation
    rest_time: float  # s


def check_settings(values: dict) -> Draft:
    """Validate what the descriptors cannot (before a change is accepted)."""
    model = RobotModel.from_params(values)
    rated = RigidBody.validated("rated_payload", values["rated_payload.mass"], values["rated_payload.com"])
    period = values["diagnostics.period"]
    if period != 0.0 and not MIN_DIAGNOSTICS_PERIOD <= period <= MAX_DIAGNOSTICS_PERIOD:
        raise ValueError(
            f"diagnostics.period: must be 0 (only on ~/check) or between {MIN_DIAGNOSTICS_PERIOD:g} "
            f"and {MAX_DIAGNOSTICS_PERIOD:g} s, got {period}"
        )
    check_choice("qos.reliability", values["qos.reliability"], RELIABILITIES)
    return Draft(
        model,
        rated,
        values["diagnostics.warn_use"],
        values["estimation.rest_velocity"],
        values["estimation.rest_time"],
        values["check.analysis_timeout"],
    )


def finish_settings(draft: Draft, previous: PayloadCheckSettings | None) -> PayloadCheckSettings:
    """Derive the limits and analyse the workspace (seconds for a large model: runs off the
    executor, within draft.analysis_timeout); what the previous settings computed for the
    same arm is reused."""
    model, rated = draft.model, draft.rated_payload
    with stopping(seconds=draft.analysis_timeout):
        limits = previous.limits if _same_arm(draft, previous) else derive_torque_limits(model, rated)
        if analysed(draft, previous):
            workspace = previous.workspace
        else:
            workspace = workspace_load(model, model.payload, limits)
    return PayloadCheckSettings(model, rated, draft.warn_use, limits, workspace, draft.rest_velocity, draft.rest_time)


def _same_arm(draft: Draft, previous: PayloadCheckSettings | None) -> bool:
    """The same torque limits as before: the same joints, gravity and rated payload."""
    return previous is not None and (previous.model.joints, previous.model.gravity, previous.rated_payload) == (
        draft.model.joints,
        draft.model.gravity,
        draft.rated_payload,
    )


def analysed(draft: Draft, previous: PayloadCheckSettings | None) -> bool:
    """Nothing to analyse: the previous settings had the same arm and payload."""
    return _same_arm(draft, previous) and previous.model.payload == draft.model.payload


class PayloadCheckNode(Node):
    def __init__(self, **kwargs):
        super().__init__("payload_check_node", **NODE_OPTIONS, **kwargs)
        self.settings: PayloadCheckSettings | None = None  # None: waiting for the model (robot_description topic)
        self._started = False
        self._state = None  # (q, qd, time received [node clock]) of the latest good joint state
        self._early = None  # (the latest joint state, time received) before the first model
        self.tally = Tally(self.get_logger())
        self.counts = self.tally.counts
        recipe = Recipe(
            NODE_PARAMETERS, check_settings, finish=finish_settings, quick=analysed, startup_wait=STARTUP_WAIT
        )
        self.parameters = declare_model_source(self, recipe)
        self.parameters.on_change(self._use)
        self.estimator = PayloadEstimator(self, self._model)
        if self.parameters.current is not None:
            self._use(self.parameters.current)

        self.create_subscription(JointState, "joint_states", self._on_joint_state, joint_states_qos(self))
        self.check_service = CheckService(self, self._on_check, lambda: self.parameters.pending_since is not None)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        period = self.get_parameter("diagnostics.period").value
        if period > 0.0:
            self.create_timer(period, self._on_timer)
        self._started = True
        if self.settings is not None:
            self._log_ready()
        elif self.parameters.pending_since is not None:
            mass, com = self.get_parameter("payload.mass").value, list(self.get_parameter("payload.com").value)
            self.get_logger().info(
                f"ready: ~/check for a {mass} kg payload at {com} m "
                "(its workspace analysis still running: ~/check waits for it)"
            )

    @property
    def model(self) -> RobotModel | None:  # the RobotModel in force; None while waiting for a URDF
        return None if self.settings is None else self.settings.model

    def _use(self, settings: PayloadCheckSettings) -> None:
        """Switch to new settings (built, limits and workspace sweep included, when checked)."""
        first, names = self.settings is None, settings.model.joint_names
        if first or names != self.settings.model.joint_names:
            self._order = JointOrder(names)
            self._state = None
            self.estimator.detector.clear()  # rest samples of other joints
        self.settings = settings
        problem = None if self._state is None else self._finite_problem(*self._state[:2])
        if problem is not None:  # a held state the new model gives no finite torques for
            self.tally.drop("joint_states", problem)
            self._state = None
        self.estimator.use(settings.rest_velocity, settings.rest_time, settings.model.friction)
        if first and self._early is not None:  # the latest joint state before the first model
            early, self._early = self._early, None
            self._take(*early)
        if first and self._started:  # the model came after startup
            self._log_ready()

    def _log_ready(self) -> None:
        payload = self.settings.model.payload
        self.get_logger().info(f"ready: ~/check for a {payload.mass} kg payload at {list(payload.com)} m")

    def _model(self) -> RobotModel:
        """The model in force, for the payload estimate."""
        if self.settings is None:
            raise EstimationError("no model yet: waiting for a URDF on the robot_description topic")
        return self.settings.model

    def _finite_problem(self, q, qd) -> BadMessage | None:
        """Why the model in force gives no finite torques at (q, qd), qdd = 0 (as id_node), or None."""
        model = self.settings.model
        try:
            finite_torques(rnea, model, q, qd, [0.0] * model.n)
            finite_torques(gravity, model, q)
        except BadMessage as error:
            return error
        return None

    @guarded("joint_states")
    def _on_joint_state(self, msg: JointState) -> None:
        self.counts["joint_states.received"] += 1
        if self.settings is None:  # the latest is kept, and taken with the first model (see _use)
            self.counts["joint_states.no_model_yet"] += 1
            self._early = (msg, self.get_clock().now())
            return
        self._take(msg, self.get_clock().now())

    def _take(self, msg: JointState, now) -> None:
        """A joint state received at ``now`` (node clock): the state checks use, and the
        payload estimate's sample; a bad one dropped, counted and warned about."""
        try:
            q, qd = read_joint_state(msg, self._order)
        except NotForThisModel:
            self.counts["joint_states.ignored"] += 1
            return
        except BadMessage as error:
            self.tally.drop("joint_states", error)
            return
        problem = self._finite_problem(q, qd)
        if problem is not None:
            self.tally.drop("joint_states", problem)
            return
        self._state = (q, qd, now)
        try:
            effort = read_effort(msg, self._order)
        except BadMessage as error:
            self.counts[f"estimation.{error.kind}"] += 1
            self.tally.warn("estimation", f"no effort of a joint state for the payload estimate ({error})")
            effort = None
        stamp = msg.header.stamp
        t = seconds(stamp.sec, stamp.nanosec)
        try:
            self.estimator.update(t if t != 0.0 else now.nanoseconds * 1e-9, q, qd, effort)
        except ValueError as error:  # an absurd effort: not averaged
            self.counts["estimation.effort_too_large"] += 1
            self.tally.warn("estimation", f"a joint state left out of the payload estimate ({error})")

    def check(self):
        """Check the payload (at the latest state, if any) and publish /diagnostics:
        (the PayloadCheck, how old the state is in words if older than STALE_AFTER, else None);
        (None, None) while there is no model."""
        settings, state = self.settings, self._state
        if settings is None:
            return None, None
        q, qd, received = state if state is not None else (None, None, None)
        result = check_payload(
            settings.model, settings.model.payload, settings.limits, q, qd, workspace=settings.workspace
        )
        stale = None if received is None else self._stale(received)
        statuses = payload_statuses(result, self.get_name(), settings.warn_use, stale)
        self._publish(statuses + [self.estimator.status(self.get_name())])
        return result, stale

    def _not_ready(self) -> str | None:
        """None when the parameters in force have been analysed; else why not (yet), for
        /diagnostics and ~/check (which first waits while an analysis is pending)."""
        status = self.parameters.status()
        if status is None and self.settings is not None:
            return None
        if self.parameters.failure is not None:
            return f"cannot check: {status}"
        since = self.parameters.pending_since
        if since is None:
            return "no model yet: waiting for a URDF on the robot_description topic"
        return (
            f"pending: the limits and workspace analysis of the new parameters are running "
            f"(for {time.monotonic() - since:.1f} s); ~/check waits for them"
        )

    def _publish(self, statuses) -> None:
        for status in statuses:  # the robot's name (model.name, or the URDF's), as rqt_robot_monitor groups them
            status.hardware_id = self.parameters.robot_name or status.hardware_id
        diagnostics = DiagnosticArray(status=statuses)
        diagnostics.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(diagnostics)

    def _stale(self, received) -> str | None:
        age = (self.get_clock().now() - received).nanoseconds * 1e-9
        return f"joint_states received {age:.1f} s ago" if age > STALE_AFTER else None

    @guarded("diagnostics")
    def _on_timer(self) -> None:
        why = self._not_ready()
        if why is None:
            self.check()
            return
        level = DiagnosticStatus.ERROR if self.parameters.failure is not None else DiagnosticStatus.WARN
        name = self.get_name()
        self._publish([DiagnosticStatus(level=level, name=f"{name}: payload", hardware_id=name, message=why)])

    def _on_check(self, request, response):
        """~/check's answer now (see check_service: it waits for the analysis first)."""
        why = self._not_ready()
        if why is not None:
            response.success, response.message = False, f"UNPROVEN: {why}"
            return response
        result, stale = self.check()
        response.success = result.ok
        response.message = result.report()
        if result.torque is None:
            response.message += "\n(no joint_states received yet: checked over the workspace only)"
        elif stale is not None:
            response.message += f"\nnote: {stale}"
        return response


def usage() -> Usage:
    """What ``payload_check_node --help`` prints: this module's docstring and every parameter."""
    return Usage("payload_check_node", __doc__, [*model_sections(), ("payload_check_node's own", NODE_PARAMETERS)])


def main(args=None):
    raise SystemExit(run("payload_check_node", PayloadCheckNode, args, usage=usage))


if __name__ == "__main__":
    main()
