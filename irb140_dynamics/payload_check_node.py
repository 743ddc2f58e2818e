"""payload_check_node: can the arm hold this payload, with what margin, how much could it hold.

Serves       ~/check        std_srvs/Trigger: the configured payload (payload.* parameters)
                            against the joint torque limits, at the current joint state (if
                            joint_states was received) and in each joint's worst static pose
                            over the joint ranges; the reply's message is the report
             ~/estimate_payload, ~/clear_samples   std_srvs/Trigger: payload estimation from the
                            efforts at rest (see ros.estimation)
Subscribes   joint_states   sensor_msgs/JointState (matched by joint name, as in id_node)
             robot_description  std_msgs/String: the model, as in id_node (see ros.model_source)
Publishes    /diagnostics   diagnostic_msgs/DiagnosticArray: one status per joint and one for
                            the payload, after each check and every diagnostics.period

Torque limits: <joint>.torque_limit when > 0, else derived as in the report: the worst
static torque of the rated payload over the joint ranges; none for a joint it cannot load.
A joint state older than STALE_AFTER (node clock) is still used, and the check says so.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from .core import RigidBody, RobotModel, rnea
from .core.payload_estimation import EstimationError
from .core.payload import TorqueLimits, WorkspaceLoad, check_payload, derive_torque_limits, workspace_load
from .ros.diagnostics import payload_statuses
from .ros.estimation import ESTIMATION_PARAMETERS, PayloadEstimator, check_estimation
from .ros.messages import BadMessage, JointOrder, NotForThisModel, count_and_warn, read_effort, read_joint_state
from .ros.model_source import declare_model_source
from .ros.params import QOS_PARAMETERS, Spec, check_qos, joint_states_qos
from .ros.spin import run

NODE_PARAMETERS = [
    Spec("rated_payload.mass", 6.0, "the rated payload the torque limits are derived from", "kg",
         minimum=0.0),
    Spec("rated_payload.com", [0.0, 0.0, 0.0], "its centre of mass, in the flange frame", "m"),
    Spec("diagnostics.warn_use", 90.0, "a joint using more of its limit than this is a WARN", "%",
         minimum=0.0),
    Spec("diagnostics.period", 1.0, "check and publish /diagnostics this often; 0 = only on ~/check",
         "s", minimum=0.0, read_only=True),
    *ESTIMATION_PARAMETERS,
    *QOS_PARAMETERS,
]
STALE_AFTER = 1.0  # s: a joint state older than this is reported as stale


@dataclass(frozen=True)
class Settings:
    """What a check needs that depends only on the parameters, the workspace sweep included."""

    model: RobotModel  # with the payload under test
    rated_payload: RigidBody
    warn_use: float
    limits: TorqueLimits
    workspace: WorkspaceLoad  # the payload's worst static loads and largest mass
    rest_velocity: float  # rad/s, payload estimation
    rest_time: float  # s


def build_settings(values: dict) -> Settings:
    """Validate everything, derive the limits and sweep the workspace: a change that fails
    here is refused, and these settings are the ones applied."""
    model = RobotModel.from_params(values)
    rated = RigidBody.validated("rated_payload", values["rated_payload.mass"], values["rated_payload.com"])
    if not values["diagnostics.warn_use"] >= 0.0:
        raise ValueError(f"diagnostics.warn_use: must be >= 0 %, got {values['diagnostics.warn_use']}")
    check_qos(values)
    check_estimation(values)
    limits = derive_torque_limits(model, rated)
    workspace = workspace_load(model, model.payload, limits)
    return Settings(
        model, rated, values["diagnostics.warn_use"], limits, workspace,
        values["estimation.rest_velocity"], values["estimation.rest_time"],
    )


class PayloadCheckNode(Node):
    def __init__(self, **kwargs):
        super().__init__("payload_check_node", **kwargs)
        self.settings: Settings | None = None  # None: waiting for the model (robot_description topic)
        self._started = False
        self._state = None  # (q, qd, time received [node clock]) of the latest good joint state
        self.parameters = declare_model_source(self, NODE_PARAMETERS, build_settings)
        self.parameters.on_change(self._use)
        self.counts: Counter[str] = Counter()
        self.estimator = PayloadEstimator(self, self._model)
        if self.parameters.current is not None:
            self._use(self.parameters.current)

        self.create_subscription(JointState, "joint_states", self._on_joint_state, joint_states_qos(self))
        self.create_service(Trigger, "~/check", self._on_check)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        period = self.get_parameter("diagnostics.period").value
        if period > 0.0:
            self.create_timer(period, self.check)
        self._started = True
        if self.settings is not None:
            self._log_ready()

    def _use(self, settings: Settings) -> None:
        """Switch to new settings (built, limits and workspace sweep included, when checked)."""
        first, names = self.settings is None, settings.model.joint_names
        if first or names != self.settings.model.joint_names:
            self._order = JointOrder(names)
            self._state = None
            self.estimator.detector.clear()  # rest samples of other joints
        self.settings = settings
        self.estimator.use(settings.rest_velocity, settings.rest_time)
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

    def _on_joint_state(self, msg: JointState) -> None:
        if self.settings is None:
            return
        try:
            q, qd = read_joint_state(msg, self._order)
        except NotForThisModel:
            return
        except BadMessage as error:
            count_and_warn(self.get_logger(), self.counts, "joint_states", error)
            return
        try:  # a state whose torques the core refuses as not finite could not be checked
            rnea(self.settings.model, q, qd, [0.0] * len(q))
        except ValueError as error:
            count_and_warn(self.get_logger(), self.counts, "joint_states", BadMessage("non_finite_torques", str(error)))
            return
        now = self.get_clock().now()
        self._state = (q, qd, now)
        try:
            effort = read_effort(msg, self._order)
        except BadMessage as error:
            count_and_warn(self.get_logger(), self.counts, "joint_states effort", error)
            effort = None
        stamp = msg.header.stamp
        t = stamp.sec + 1e-9 * stamp.nanosec
        self.estimator.update(t if t != 0.0 else now.nanoseconds * 1e-9, q, qd, effort)

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
        diagnostics = DiagnosticArray(status=statuses + [self.estimator.status(self.get_name())])
        diagnostics.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(diagnostics)
        return result, stale

    def _stale(self, received) -> str | None:
        age = (self.get_clock().now() - received).nanoseconds * 1e-9
        return f"joint_states received {age:.1f} s ago" if age > STALE_AFTER else None

    def _on_check(self, request, response):
        result, stale = self.check()
        if result is None:
            response.success = False
            response.message = "no model yet: waiting for a URDF on the robot_description topic"
            return response
        response.success = result.ok
        response.message = result.report()
        if result.torque is None:
            response.message += "\n(no joint_states received yet: checked over the workspace only)"
        elif stale is not None:
            response.message += f"\nnote: {stale}"
        return response


def main(args=None):
    raise SystemExit(run("payload_check_node", PayloadCheckNode, args))


if __name__ == "__main__":
    main()
