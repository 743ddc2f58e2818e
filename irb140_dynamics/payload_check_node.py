"""payload_check_node: can the arm hold this payload, with what margin, how much could it hold.

Serves       ~/check        std_srvs/Trigger: the configured payload (payload.* parameters)
                            against the joint torque limits, at the current joint state (if
                            joint_states was received) and in each joint's worst static pose
                            over the joint ranges; the reply's message is the report
Subscribes   joint_states   sensor_msgs/JointState (matched by joint name, as in id_node)
Publishes    /diagnostics   diagnostic_msgs/DiagnosticArray: one status per joint and one for
                            the payload, after each check and every diagnostics.period

Torque limits: <joint>.torque_limit when > 0, else derived as in the report: the worst
static torque of the rated payload over the joint ranges; none for a joint gravity cannot load.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger

from .core import RigidBody, RobotModel
from .core.payload import check_payload, derive_torque_limits, workspace_load
from .ros.diagnostics import payload_statuses
from .ros.messages import BadMessage, JointOrder, count_and_warn, read_joint_state
from .ros.params import QOS_PARAMETERS, Spec, check_qos, declare_model, joint_states_qos
from .ros.spin import run

NODE_PARAMETERS = [
    Spec("rated_payload.mass", 6.0, "the rated payload the torque limits are derived from", "kg",
         minimum=0.0),
    Spec("rated_payload.com", [0.0, 0.0, 0.0], "its centre of mass, in the flange frame", "m"),
    Spec("diagnostics.warn_use", 90.0, "a joint using more of its limit than this is a WARN", "%",
         minimum=0.0),
    Spec("diagnostics.period", 1.0, "check and publish /diagnostics this often; 0 = only on ~/check",
         "s", minimum=0.0, read_only=True),
    *QOS_PARAMETERS,
]


@dataclass(frozen=True)
class Settings:
    model: RobotModel  # with the payload under test
    rated_payload: RigidBody
    warn_use: float


def build_settings(values: dict) -> Settings:
    model = RobotModel.from_params(values)
    rated = RigidBody.validated("rated_payload", values["rated_payload.mass"], values["rated_payload.com"])
    if not values["diagnostics.warn_use"] >= 0.0:
        raise ValueError(f"diagnostics.warn_use: must be >= 0 %, got {values['diagnostics.warn_use']}")
    check_qos(values)
    return Settings(model, rated, values["diagnostics.warn_use"])


@dataclass(frozen=True)
class Analysis:
    """What a check needs that depends only on the settings: the limits, the workspace load."""

    settings: Settings
    limits: object
    workspace: object

    @classmethod
    def of(cls, settings: Settings) -> "Analysis":
        limits = derive_torque_limits(settings.model, settings.rated_payload)
        return cls(settings, limits, workspace_load(settings.model, settings.model.payload, limits))


class PayloadCheckNode(Node):
    def __init__(self, **kwargs):
        super().__init__("payload_check_node", **kwargs)
        self.parameters = declare_model(self, NODE_PARAMETERS, build_settings)
        self.parameters.on_change(self._use)
        self.counts: Counter[str] = Counter()
        self._use(self.parameters.current)
        self._order = JointOrder(self.analysis.settings.model.joint_names)
        self._state = None  # (q, qd) of the latest good joint state

        self.create_subscription(JointState, "joint_states", self._on_joint_state, joint_states_qos(self))
        self.create_service(Trigger, "~/check", self._on_check)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        period = self.get_parameter("diagnostics.period").value
        if period > 0.0:
            self.create_timer(period, self.check)
        payload = self.analysis.settings.model.payload
        self.get_logger().info(f"ready: ~/check for a {payload.mass} kg payload at {list(payload.com)} m")

    def _use(self, settings: Settings) -> None:
        """New settings: derive the limits and sweep the workspace now, then swap in one step."""
        self.analysis = Analysis.of(settings)

    def _on_joint_state(self, msg: JointState) -> None:
        try:
            self._state = read_joint_state(msg, self._order)
        except BadMessage as error:
            count_and_warn(self.get_logger(), self.counts, "joint_states", error)

    def check(self):
        """Check the payload (at the current state, if known) and publish /diagnostics."""
        analysis, state = self.analysis, self._state
        settings = analysis.settings
        q, qd = state if state is not None else (None, None)
        result = check_payload(
            settings.model, settings.model.payload, analysis.limits, q, qd, workspace=analysis.workspace
        )
        diagnostics = DiagnosticArray(status=payload_statuses(result, self.get_name(), settings.warn_use))
        diagnostics.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(diagnostics)
        return result

    def _on_check(self, request, response):
        result = self.check()
        response.success = result.ok
        response.message = result.report()
        if result.torque is None:
            response.message += "\n(no joint_states received yet: checked over the workspace only)"
        return response


def main(args=None):
    raise SystemExit(run("payload_check_node", PayloadCheckNode, args))


if __name__ == "__main__":
    main()
