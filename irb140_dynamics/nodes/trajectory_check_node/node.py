"""trajectory_check_node: will a JointTrajectory keep the arm's limits, and how fast could
the same path go.

Subscribes   ~/check_trajectory   trajectory_msgs/JointTrajectory: checked as
                                  joint_trajectory_controller plays it (see
                                  core.trajectories.check), reported on ~/trajectory_report
             ~/retime             trajectory_msgs/JointTrajectory: re-timed time-optimally,
                                  published on ~/retimed, its check on ~/trajectory_report
             <watch_topic>        (parameter; e.g. /joint_trajectory_controller/joint_trajectory)
                                  checked like ~/check_trajectory: a watch on what the
                                  controller is sent
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

from dataclasses import dataclass

from diagnostic_msgs.msg import DiagnosticStatus
from rclpy.node import Node
from trajectory_msgs.msg import JointTrajectory

from irb140_dynamics.core import RobotModel
from irb140_dynamics.core.errors import one_line
from irb140_dynamics.core.trajectories import (
    Limits,
    TrajectoryError,
    check_trajectory,
    retime,
    torque_limit_notes,
    trajectory_limits,
)
from irb140_dynamics.nodes.trajectory_check_node.messages import (
    error_status,
    report_status,
    trajectory_message,
    trajectory_of,
)
from irb140_dynamics.ros.parameters.live import Recipe
from irb140_dynamics.ros.parameters.model_source import declare_model_source
from irb140_dynamics.ros.parameters.overrides import NODE_OPTIONS
from irb140_dynamics.ros.parameters.specs import Spec
from irb140_dynamics.ros.parameters.usage import model_sections
from irb140_dynamics.ros.runtime.command_line import Usage
from irb140_dynamics.ros.runtime.guard import Tally, guarded
from irb140_dynamics.ros.runtime.spin import run

MAX_WARN_USE = 1e6  # %
MIN_GRID, MAX_GRID = 10, 100_000
NODE_PARAMETERS = [
    Spec(
        "watch_topic",
        "",
        "also check every JointTrajectory on this topic (e.g. /joint_trajectory_controller/joint_trajectory); "
        "empty: none",
        read_only=True,
    ),
    Spec("retime.grid", 1000, "grid steps over the path when re-timing, about", minimum=MIN_GRID, maximum=MAX_GRID),
    Spec(
        "diagnostics.warn_use",
        90.0,
        "a trajectory using more of a limit than this is a WARN",
        "%",
        minimum=0.0,
        maximum=MAX_WARN_USE,
    ),
]
STARTUP_WAIT = 2.0  # s: at most this long for the torque limits before the node comes up


@dataclass(frozen=True)
class Draft:
    model: RobotModel
    grid: int
    warn_use: float


@dataclass(frozen=True)
class TrajectoryCheckSettings:
    model: RobotModel
    grid: int
    warn_use: float
    limits: Limits
    notes: tuple[str, ...]  # where the torque limits come from


def check_settings(values: dict) -> Draft:
    return Draft(RobotModel.from_params(values), values["retime.grid"], values["diagnostics.warn_use"])


def finish_settings(draft: Draft, previous: TrajectoryCheckSettings | None) -> TrajectoryCheckSettings:
    """The torque limits (derived off the executor when the params leave them at 0)."""
    same = previous is not None and (previous.model.joints, previous.model.gravity) == (
        draft.model.joints,
        draft.model.gravity,
    )
    limits = previous.limits if same else trajectory_limits(draft.model)
    return TrajectoryCheckSettings(
        draft.model, draft.grid, draft.warn_use, limits, torque_limit_notes(draft.model, limits)
    )


def quick(draft: Draft, previous: TrajectoryCheckSettings | None) -> bool:
    return previous is not None and (previous.model.joints, previous.model.gravity) == (
        draft.model.joints,
        draft.model.gravity,
    )


class TrajectoryCheckNode(Node):
    def __init__(self, **kwargs):
        super().__init__("trajectory_check_node", **NODE_OPTIONS, **kwargs)
        self.tally = Tally(self.get_logger())
        self.counts = self.tally.counts
        recipe = Recipe(NODE_PARAMETERS, check_settings, finish=finish_settings, quick=quick, startup_wait=STARTUP_WAIT)
        self.parameters = declare_model_source(self, recipe)
        self._report_pub = self.create_publisher(DiagnosticStatus, "~/trajectory_report", 10)
        self._retimed_pub = self.create_publisher(JointTrajectory, "~/retimed", 10)
        self.create_subscription(JointTrajectory, "~/check_trajectory", self._on_check, 10)
        self.create_subscription(JointTrajectory, "~/retime", self._on_retime, 10)
        watch = self.get_parameter("watch_topic").value
        if watch:
            self.create_subscription(JointTrajectory, watch, self._on_watch, 10)
        self.get_logger().info("ready: ~/check_trajectory and ~/retime" + (f", watching {watch}" if watch else ""))

    @property
    def settings(self) -> TrajectoryCheckSettings | None:
        return self.parameters.current

    @property
    def model(self) -> RobotModel | None:
        """The RobotModel in force; None while waiting for a URDF."""
        return None if self.settings is None else self.settings.model

    def _not_ready(self) -> str:
        if self.parameters.failure is not None:
            return f"cannot check: {self.parameters.status()}"
        if self.parameters.pending_since is not None:
            return "not checked: the torque limits are being derived; send it again shortly"
        return "no model yet: waiting for a URDF on the robot_description topic"

    def _name(self, what: str) -> str:
        return f"{self.get_name()}: {what}"

    def _refuse(self, topic: str, what: str, reason: str) -> None:
        """An ERROR report for a message that cannot be checked; counted, warned (throttled)."""
        self.tally.add(topic, "refused")
        self.tally.warn(topic, f"refused a {topic} message: {reason}")
        self._report_pub.publish(error_status(reason, self._name(what), self.get_name()))

    def _trajectory(self, topic: str, what: str, msg: JointTrajectory):
        self.counts[f"{topic}.received"] += 1
        settings = self.settings
        if settings is None:
            self._refuse(topic, what, self._not_ready())
            return None, None
        try:
            return settings, trajectory_of(msg, settings.model.joint_names)
        except TrajectoryError as error:
            self._refuse(topic, what, one_line(error))
            return None, None

    def _check(self, topic: str, msg: JointTrajectory) -> None:
        settings, tr = self._trajectory(topic, "trajectory", msg)
        if tr is None:
            return
        report = check_trajectory(settings.model, tr, settings.limits)
        status = report_status(report, self._name("trajectory"), self.get_name(), settings.warn_use, settings.notes)
        self._report_pub.publish(status)

    @guarded("check_trajectory")
    def _on_check(self, msg: JointTrajectory) -> None:
        self._check("check_trajectory", msg)

    @guarded("watch")
    def _on_watch(self, msg: JointTrajectory) -> None:
        self._check("watch", msg)

    @guarded("retime")
    def _on_retime(self, msg: JointTrajectory) -> None:
        settings, tr = self._trajectory("retime", "retimed", msg)
        if tr is None:
            return
        try:
            result = retime(settings.model, tr, settings.limits, grid=settings.grid)
        except TrajectoryError as error:
            self._refuse("retime", "retimed", one_line(error))
            return
        out = trajectory_message(result.trajectory, msg.header.frame_id)
        self._retimed_pub.publish(out)
        report = check_trajectory(settings.model, result.trajectory, settings.limits)
        notes = (*settings.notes, f"re-timed from {tr.duration:.6f} s, {len(out.points)} points")
        status = report_status(report, self._name("retimed"), self.get_name(), settings.warn_use, notes)
        self._report_pub.publish(status)


def usage() -> Usage:
    """What ``trajectory_check_node --help`` prints: this module's docstring and every parameter."""
    return Usage(
        "trajectory_check_node", __doc__, [*model_sections(), ("trajectory_check_node's own", NODE_PARAMETERS)]
    )


def main(args=None):
    raise SystemExit(run("trajectory_check_node", TrajectoryCheckNode, args, usage=usage))


if __name__ == "__main__":
    main()
