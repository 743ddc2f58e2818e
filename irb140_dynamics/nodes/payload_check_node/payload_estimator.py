"""payload_check_node's payload estimation: the ROS side of core.payload.mass_com_estimation.

Serves       ~/estimate_payload   std_srvs/Trigger: mass and CoM from the rest poses seen so far
             ~/clear_samples      std_srvs/Trigger: forget them and the last estimate
"""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from rclpy.node import Node
from rclpy.parameter import Parameter
from std_srvs.srv import Trigger

from irb140_dynamics.core.model.friction import JointFriction
from irb140_dynamics.core.payload.mass_com_estimation import (
    EstimationError,
    PayloadEstimate,
    RestDetector,
    estimate_payload,
)
from irb140_dynamics.ros.parameters.specs import Spec
from irb140_dynamics.ros.runtime.guard import guarded

MAX_REST_VELOCITY = 1e3  # rad/s
MAX_REST_TIME = 3600.0  # s
ESTIMATION_PARAMETERS = [
    Spec(
        "estimation.rest_velocity",
        0.02,
        "a joint state is at rest when every joint is slower than this",
        "rad/s",
        minimum=1e-6,
        maximum=MAX_REST_VELOCITY,
    ),
    Spec(
        "estimation.rest_time",
        0.5,
        "a rest this long becomes a sample (one per distinct pose)",
        "s",
        minimum=0.0,
        maximum=MAX_REST_TIME,
    ),
    Spec("estimation.apply", False, "on a successful ~/estimate_payload, set payload.mass and payload.com"),
]


def _failed(what: str):
    """A guarded service's answer to an exception of ours."""

    def answer(request, response, error):
        response.success = False
        response.message = f"{what}: internal error {type(error).__name__}: {error}"
        return response

    return answer


class PayloadEstimator:
    """Collects rest samples from joint states and answers ~/estimate_payload."""

    def __init__(self, node: Node, model_of):
        """``model_of()``: the model in force (the arm the efforts are set against)."""
        self._node, self._model_of = node, model_of
        self.tally = node.tally  # for guarded
        self.detector = RestDetector(
            node.get_parameter("estimation.rest_velocity").value, node.get_parameter("estimation.rest_time").value
        )
        self.last: PayloadEstimate | None = None
        self._efforts_missing = False
        node.create_service(Trigger, "~/estimate_payload", self._on_estimate)
        node.create_service(Trigger, "~/clear_samples", self._on_clear)

    def use(self, rest_velocity: float, rest_time: float, friction: JointFriction | None) -> None:
        """The settings in force; ``friction``: the model's, taken off the efforts at rest."""
        self.detector.rest_velocity, self.detector.rest_time = rest_velocity, rest_time
        self.detector.friction = friction

    def update(self, t: float, q, qd, effort) -> None:
        """One joint state (effort None when the message has none)."""
        self._efforts_missing = effort is None
        self.detector.update(t, q, qd, effort)

    def _missing_effort(self) -> str | None:
        """What the joint states' missing efforts cost, or None."""
        advice = "the driver must publish JointState.effort (the measured joint torques)"
        poses = len(self.detector.without_effort)
        if poses:
            return f"{poses} rest pose{'s' if poses > 1 else ''} had no effort in joint_states: {advice}"
        if self._efforts_missing and not self.detector.samples:
            return f"joint_states carry no effort: {advice}"
        return None

    @guarded("estimate_payload", fallback=_failed("cannot estimate"))
    def _on_estimate(self, request, response):
        self.detector.flush()
        missing = self._missing_effort()
        try:
            self.last = estimate_payload(self._model_of(), self.detector.samples)
        except EstimationError as error:
            if missing is None:
                why = str(error)
            else:  # the missing efforts first: they are what to fix
                why = missing if not self.detector.samples else f"{missing}; {error}"
            response.success, response.message = False, f"cannot estimate: {why}"
            return response
        response.success, response.message = True, self.last.summary()
        if self.detector.without_effort:
            response.message += f"\nnote: {missing}"
        if self._node.get_parameter("estimation.apply").value:
            response.success, note = self._apply(self.last)
            response.message += f"\n{note}"
        return response

    def _apply(self, estimate: PayloadEstimate) -> tuple[bool, str]:
        """Set payload.mass and payload.com through the validated parameter path."""
        result = self._node.set_parameters_atomically(
            [
                Parameter("payload.mass", Parameter.Type.DOUBLE, float(estimate.mass)),
                Parameter("payload.com", Parameter.Type.DOUBLE_ARRAY, [float(x) for x in estimate.com]),
            ]
        )
        if result.successful:
            return True, "applied: payload.mass and payload.com set"
        return False, f"not applied: {result.reason}"

    @guarded("clear_samples", fallback=_failed("not cleared"))
    def _on_clear(self, request, response):
        count, estimate = len(self.detector.samples), self.last is not None
        self.detector.clear()
        self.last = None  # an estimate of what may no longer be mounted
        response.success = True
        response.message = f"forgot {count} rest samples" + (" and the last estimate" if estimate else "")
        return response

    def status(self, node_name: str) -> DiagnosticStatus:
        samples = len(self.detector.samples)
        values = [KeyValue(key="rest samples", value=str(samples))]
        message = f"{samples} rest samples"
        if self.last is not None:
            message += f"; last estimate: {self.last.summary()}"
            values += [
                KeyValue(key="estimated mass [kg]", value=f"{self.last.mass:.3f}"),
                KeyValue(key="estimated CoM [m]", value=", ".join(f"{x:.4f}" for x in self.last.com)),
            ]
        return DiagnosticStatus(
            level=DiagnosticStatus.OK,
            name=f"{node_name}: payload estimation",
            hardware_id=node_name,
            message=message,
            values=values,
        )
