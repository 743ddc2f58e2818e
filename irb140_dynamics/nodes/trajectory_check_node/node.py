"""trajectory_check_node: will a JointTrajectory keep the arm's limits, and how fast could
the same path go.

Subscribes   ~/check_trajectory   trajectory_msgs/JointTrajectory: checked as ros2_control's
                                  joint_trajectory_controller plays it, reported
             ~/retime             trajectory_msgs/JointTrajectory: re-timed time-optimally,
                                  published on ~/retimed, its check reported
             <watch_topic>        (e.g. /joint_trajectory_controller/joint_trajectory) checked
                                  like ~/check_trajectory: a watch on what the controller is sent
             robot_description    std_msgs/String: the model, as in the other nodes
Publishes    ~/trajectory_report  diagnostic_msgs/DiagnosticStatus: the duration, a KeyValue per
                                  joint and limit (peak, limit, use, when, which segment); OK,
                                  WARN from diagnostics.warn_use %, ERROR over a limit, or for a
                                  message that cannot be checked (the reason, one line)
             ~/retimed            trajectory_msgs/JointTrajectory: the re-timed trajectory

Torque limits: <joint>.torque_limit when > 0, else derived as payload_check_node derives them
(the worst static torque of the rated payload over the joint ranges); the report says so. The
model's payload (payload.*), friction and armature count.
"""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectory

from irb140_dynamics.core import RobotModel
from irb140_dynamics.core.errors import one_line
from irb140_dynamics.core.trajectories import TrajectoryChecker, TrajectoryError
from irb140_dynamics.node_help import Usage
from irb140_dynamics.ros.messages.joint_messages import trajectory_message, trajectory_of
from irb140_dynamics.ros.parameters.arm import DESCRIPTION_QOS, ArmParameters
from irb140_dynamics.ros.parameters.overrides import NODE_OPTIONS
from irb140_dynamics.ros.parameters.specs import Spec
from irb140_dynamics.ros.parameters.usage import model_sections
from irb140_dynamics.ros.runtime.guard import Tally, guarded
from irb140_dynamics.ros.runtime.rebuild import Rebuild
from irb140_dynamics.ros.runtime.spin import run

NODE_PARAMETERS = [
    Spec("watch_topic", "", "also check every JointTrajectory on this topic (the controller's); empty: none", "", True),
    Spec("retime.grid", 1000, "grid steps over the path when re-timing, about", minimum=10, maximum=100_000),
    Spec("diagnostics.warn_use", 90.0, "a trajectory using more of a limit than this is a WARN", "%", False, 0.0, 1e6),
]
STARTUP_WAIT = 2.0  # s: at most this long for the torque limits before the node comes up
WAITING = "no model yet: waiting for a URDF on the robot_description topic"
LEVELS = {"ok": DiagnosticStatus.OK, "warn": DiagnosticStatus.WARN, "error": DiagnosticStatus.ERROR}


def draft(values: dict) -> tuple[RobotModel, int, float]:
    """What a checker is built from (the model checked whole), its limits not derived yet."""
    return RobotModel.from_params(values), values["retime.grid"], values["diagnostics.warn_use"]


class TrajectoryCheckNode(Node):
    """Trajectories in; a report each, and the re-timed ones, out."""

    def __init__(self, **kwargs):
        super().__init__("trajectory_check_node", **NODE_OPTIONS, **kwargs)
        self.tally = Tally(self.get_logger())
        self.counts = self.tally.counts
        self.checker: TrajectoryChecker | None = None  # None: not built yet, or waiting for a URDF
        self.parameters = ArmParameters(self, NODE_PARAMETERS)
        self.rebuild = Rebuild(self, lambda job, previous: TrajectoryChecker.of(*job, previous), self._use)
        self._reader = Rebuild(self, self.parameters.read_topic, self._take_urdf)
        self._draft = None  # the draft of a change accepted by _on_set, for _on_set_done
        first = self.parameters.draft(draft, self.parameters.values())
        if first is not None:
            self.rebuild.submit(first)
            self.rebuild.wait(STARTUP_WAIT)  # the torque limits, if quick; else they follow
        self.add_on_set_parameters_callback(self._on_set)
        self.add_post_set_parameters_callback(self._on_set_done)
        if self.parameters.from_topic:
            self.create_subscription(String, "robot_description", self._on_description, DESCRIPTION_QOS)
        self._report_pub = self.create_publisher(DiagnosticStatus, "~/trajectory_report", 10)
        self._retimed_pub = self.create_publisher(JointTrajectory, "~/retimed", 10)
        self.create_subscription(JointTrajectory, "~/check_trajectory", self._on_check, 10)
        self.create_subscription(JointTrajectory, "~/retime", self._on_retime, 10)
        watch = self.get_parameter("watch_topic").value
        if watch:
            self.create_subscription(JointTrajectory, watch, self._on_watch, 10)
        self.get_logger().info("ready: ~/check_trajectory and ~/retime" + (f", watching {watch}" if watch else ""))

    @property
    def model(self) -> RobotModel | None:
        """The model in force (None while waiting for a URDF)."""
        return None if self.checker is None else self.checker.model

    def _use(self, checker: TrajectoryChecker) -> None:
        self.checker = checker

    def _on_set(self, parameters) -> SetParametersResult:
        """A change is accepted only if the whole new configuration checks."""
        result, self._draft = self.parameters.check_change(parameters, draft)
        return result

    def _on_set_done(self, parameters) -> None:
        """The change accepted: in force at once when the torque limits stay, else derived
        off the executor meanwhile."""
        job, previous, self._draft = self._draft, self.rebuild.previous, None
        if job is not None and previous is not None and previous.keeps_limits(job[0]):
            self.rebuild.build_here(job)
        elif job is not None:
            self.rebuild.submit(job)

    def _on_description(self, msg: String) -> None:
        """A new URDF: read off the executor, then checked (``_take_urdf``)."""
        self._reader.submit(msg.data)

    def _take_urdf(self, urdf) -> None:
        job = self.parameters.take_urdf(urdf, draft)
        if job is not None:
            self.rebuild.submit(job)

    def _answer(self, topic: str, what: str, msg: JointTrajectory) -> None:
        """Check (``what`` 'trajectory') or re-time ('retimed') the message and report it:
        an ERROR report, counted and warned about, when it cannot be."""
        self.counts[f"{topic}.received"] += 1
        checker, name, notes = self.checker, f"{self.get_name()}: {what}", ()
        try:
            if checker is None:
                raise TrajectoryError(f"not checked: {self.rebuild.status() or WAITING}")
            tr = trajectory_of(msg, checker.model.joint_names)
            if what == "retimed":
                retimed, report = checker.retime(tr)
                self._retimed_pub.publish(out := trajectory_message(retimed, msg.header.frame_id))
                notes = (f"re-timed from {tr.duration:.6f} s, {len(out.points)} points",)
            else:
                report = checker.check(tr)
        except TrajectoryError as error:
            self.tally.add(topic, "refused")
            self.tally.warn(topic, f"refused a {topic} message: {one_line(error)}")
            self._report(name, "error", one_line(error))
            return
        self._report(name, checker.level(report), report.headline(), checker.figures(report, notes))

    def _report(self, name: str, level: str, message: str, figures=()) -> None:
        """A DiagnosticStatus of ``level`` ('ok', 'warn', 'error') with (key, value) ``figures``."""
        values = [KeyValue(key=key, value=value) for key, value in figures]
        hardware_id = self.get_name()
        self._report_pub.publish(
            DiagnosticStatus(level=LEVELS[level], name=name, hardware_id=hardware_id, message=message, values=values)
        )

    @guarded("check_trajectory")
    def _on_check(self, msg: JointTrajectory) -> None:
        self._answer("check_trajectory", "trajectory", msg)

    @guarded("watch")
    def _on_watch(self, msg: JointTrajectory) -> None:
        self._answer("watch", "trajectory", msg)

    @guarded("retime")
    def _on_retime(self, msg: JointTrajectory) -> None:
        self._answer("retime", "retimed", msg)


def usage() -> Usage:
    """What ``trajectory_check_node --help`` prints: this module's docstring and every parameter."""
    own = ("trajectory_check_node's own", NODE_PARAMETERS)
    return Usage("trajectory_check_node", __doc__, [*model_sections(), own])


def main(args=None):
    raise SystemExit(run("trajectory_check_node", TrajectoryCheckNode, args, usage=usage))
