"""sim_node: a simulated arm (MuJoCo) that takes joint torques and publishes joint states.

Subscribes   effort_commands   std_msgs/Float64MultiArray: joint torques [N m], model joint
                               order (as ros2_control's JointGroupEffortController ~/commands)
Publishes    joint_states      sensor_msgs/JointState every step: position, velocity, effort =
                               the torque applied, named, stamped
             /diagnostics      diagnostic_msgs/DiagnosticArray, 1 Hz: steps, late steps, commands
Serves       ~/reset           std_srvs/Trigger: back to initial_positions, at rest

The true arm is the model of the parameters or of a URDF (``model.source``, as every node's)
and may differ from the model a controller uses. A command is held (zero-order hold) until
the next; once it is older than command_timeout, zero torque is applied. The engine steps
at ``rate`` in real time (sub-steps allowed) in a thread of its own, catching up late steps
(counted) and skipping when far behind (counted). Bad commands (wrong length, NaN or
infinite) are dropped, counted and warned about, never applied. See docs/sim.md.
"""

from __future__ import annotations

import threading
import time
from collections import Counter
from dataclasses import dataclass

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger

from .core import RobotModel
from .ros.messages import BadMessage, count_and_warn
from .ros.model_source import STAND_IN, declare_model_source
from .ros.params import Spec, check_choice
from .ros.spin import run
from .sim.engine import DEFAULT_INTEGRATOR, SimulatedArm, SimulationError
from .sim.mjcf import INTEGRATORS
from .sim.realtime import RealTimeLoop

WARN_LATE_SHARE = 0.01  # /diagnostics WARN when more of the last period's steps were late

NODE_PARAMETERS = [
    Spec("rate", 1000.0, "simulation steps (and joint_states messages) per second", "Hz",
         minimum=1.0, maximum=100000.0, read_only=True),
    Spec("substeps", 1, "MuJoCo steps per step (the integration step is 1 / (rate * substeps))",
         read_only=True),
    Spec("integrator", DEFAULT_INTEGRATOR, f"MuJoCo's integrator: {', '.join(INTEGRATORS)}", read_only=True),
    Spec("command_timeout", 0.1, "zero torque once the last command is older than this; 0 = never", "s",
         minimum=0.0),
    Spec("initial_positions", Parameter.Type.DOUBLE_ARRAY,
         "where the arm starts and ~/reset puts it, model joint order; not given or empty = all zero", "rad"),
    Spec("reset_hold", 0.0, "after startup and each ~/reset the arm is held still (brakes on, no torque) "
         "this long", "s", minimum=0.0),
    Spec("noise.position", 0.0, "std dev of the noise added to the published positions", "rad", minimum=0.0),
    Spec("noise.effort", 0.0, "std dev of the noise added to the published efforts", "N m", minimum=0.0),
    Spec("thread_priority", 0, "SCHED_FIFO priority (1..99) of the stepping and executor threads, as "
         "ros2_control's controller manager runs its loop; 0 = ordinary scheduling", read_only=True),
    Spec("qos.depth", 10, "queue depth of joint_states and effort_commands", read_only=True),
]


@dataclass(frozen=True)
class Settings:
    """What the node runs on, built and validated from all of its parameters at once."""

    model: RobotModel
    engine: SimulatedArm  # a fresh engine for this model: taken over (with the state) when applied
    initial_positions: np.ndarray
    command_timeout: float
    reset_hold: float
    position_noise: float
    effort_noise: float


def build_settings(values: dict) -> Settings:
    """Validate everything and compile the MuJoCo model here, not on a step."""
    model = RobotModel.from_params(values)
    waiting = model.joint_names == STAND_IN.joint_names  # checked on a stand-in until a URDF comes
    check_choice("integrator", values["integrator"], INTEGRATORS)
    if values["substeps"] < 1:
        raise ValueError(f"substeps: must be >= 1, got {values['substeps']}")
    if not 0 <= values["thread_priority"] <= 99:
        raise ValueError(f"thread_priority: must be 0..99, got {values['thread_priority']}")
    if values["qos.depth"] < 1:
        raise ValueError(f"qos.depth: must be >= 1, got {values['qos.depth']}")
    engine = SimulatedArm(model, 1.0 / values["rate"], values["substeps"], values["integrator"])
    initial = np.zeros(model.n) if waiting else initial_positions(model, values["initial_positions"])
    return Settings(model, engine, initial, values["command_timeout"], values["reset_hold"],
                    values["noise.position"], values["noise.effort"])


def initial_positions(model: RobotModel, values) -> np.ndarray:
    """The initial positions, or ValueError: one per joint (none: zeros), within the limits."""
    q = np.zeros(model.n) if not values else np.array(values, dtype=float)
    if q.shape != (model.n,):
        raise ValueError(f"initial_positions: expected {model.n} values, got {len(q)}")
    for joint, x in zip(model.joints, q):
        lower, upper = joint.position_limits
        if not lower <= x <= upper:
            raise ValueError(f"initial_positions: {joint.name} at {x} rad is outside its limits [{lower}, {upper}]")
    return q


def read_command(msg: Float64MultiArray, n: int) -> np.ndarray:
    """The torques of a command, or BadMessage: n finite numbers."""
    if len(msg.data) != n:
        raise BadMessage("length_mismatch", f"{len(msg.data)} torques for {n} joints")
    tau = np.array(msg.data, dtype=float)
    if not np.isfinite(tau).all():
        raise BadMessage("not_finite", f"torques are not finite: {tau.tolist()}")
    return tau


class SimNode(Node):
    """The simulated arm: torques in, joint states out, in real time."""

    def __init__(self, **kwargs):
        super().__init__("sim_node", **kwargs)
        self.settings: Settings | None = None  # None: waiting for the model (robot_description topic)
        self.arm: SimulatedArm | None = None  # the engine, stepped by self.loop under self._lock
        self._lock = threading.Lock()  # the arm and settings: the stepping thread against callbacks
        self.parameters = declare_model_source(self, NODE_PARAMETERS, build_settings)
        self.parameters.on_change(self._use)
        self.counts: Counter[str] = Counter()
        self._reported = Counter()  # the counts at the last diagnostics
        self._command = None  # (time received [s, monotonic], torques)
        self._command_stale = True
        self._rng = np.random.default_rng()
        self._stamp_offset = self.get_clock().now().nanoseconds - time.monotonic_ns()  # node clock - monotonic
        self.last_stamp = 0  # ns, node clock: of the last state stepped (and published)
        self.reset_stamp = 0  # ns, node clock: states stamped later were stepped after the last reset
        self._held_until = 0.0

        depth = self.get_parameter("qos.depth").value
        self._state_pub = self.create_publisher(JointState, "joint_states", depth)
        commands_qos = QoSProfile(depth=depth, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.create_subscription(Float64MultiArray, "effort_commands", self._on_command, commands_qos)
        self.create_service(Trigger, "~/reset", self._on_reset)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self.create_timer(1.0, self._publish_diagnostics)
        self.loop = RealTimeLoop(1.0 / self.get_parameter("rate").value, self._step, self._on_step_error)
        self.schedule = self.loop.schedule
        if self.parameters.current is not None:
            self._use(self.parameters.current)

    def destroy_node(self):
        self.loop.stop()
        return super().destroy_node()

    def _use(self, settings: Settings) -> None:
        """Switch to new settings: a new model of the same joints continues from the current
        state; other joints (a new URDF) start at initial_positions. The first starts the loop."""
        names = list(settings.model.joint_names)
        with self._lock:
            first = self.arm is None
            new_joints = first or names != list(self.arm.model.joint_names)
            if new_joints or settings.model != self.arm.model:
                if not new_joints:
                    settings.engine.take_state_of(self.arm)
                self.arm = settings.engine
            self.settings = settings
            if new_joints:
                self._state_msg = JointState(name=names)
                self._command = None
                self._reset()
        if first:
            refused = self.loop.start(self.get_parameter("thread_priority").value)
            if refused:
                self.get_logger().warning(f"thread_priority refused ({refused}): ordinary scheduling")
            self.get_logger().info(f"ready: {len(names)} joints {names}, {1.0 / self.schedule.period:g} Hz, "
                                   f"payload {settings.model.payload.mass} kg")

    def reset(self) -> bool:
        """The arm back at initial_positions, at rest, held for reset_hold; False without a model."""
        with self._lock:
            if self.arm is None:
                return False
            self._reset()
        return True

    def _reset(self) -> None:
        self.arm.reset(self.settings.initial_positions)
        self.reset_stamp = self.last_stamp
        self._held_until = time.monotonic() + self.settings.reset_hold
        self.counts["resets"] += 1

    def _on_reset(self, request, response):
        response.success = self.reset()
        response.message = (f"reset to {self.settings.initial_positions.tolist()} rad" if response.success
                            else "no model yet: waiting for robot_description")
        return response

    def _on_command(self, msg: Float64MultiArray) -> None:
        self.counts["commands"] += 1
        arm = self.arm
        if arm is None:
            self.counts["no_model_yet"] += 1
            return
        try:
            tau = read_command(msg, arm.n)
        except BadMessage as error:
            count_and_warn(self.get_logger(), self.counts, "effort_commands", error)
            return
        self._command = (time.monotonic(), tau)
        self._command_stale = False

    def _held_command(self, now: float) -> np.ndarray:
        """The last command while it is fresh, else zero torque."""
        if self._command is None:
            return np.zeros(self.arm.n)
        received, tau = self._command
        timeout = self.settings.command_timeout
        if timeout > 0.0 and now - received > timeout:
            if not self._command_stale:
                self._command_stale = True
                self.counts["command_timeouts"] += 1
            return np.zeros(self.arm.n)
        return tau

    def _step(self, k: int, t: float) -> None:
        """Step k of the stepping thread, due at t (monotonic): apply the held command for one
        period (none while held after a reset), then publish the state."""
        if not self.context.ok():
            return
        with self._lock:
            arm, settings = self.arm, self.settings
            now = time.monotonic()
            if now < self._held_until:
                arm.applied = np.zeros(arm.n)
            else:
                arm.step(self._held_command(now))
            q, qd, effort, msg = arm.q, arm.qd, arm.applied, self._state_msg
            stamp = self.last_stamp = self._stamp_offset + round(t * 1e9)  # node clock, ns
        if settings.position_noise > 0.0:
            q += self._rng.normal(0.0, settings.position_noise, arm.n)
        if settings.effort_noise > 0.0:
            effort = effort + self._rng.normal(0.0, settings.effort_noise, arm.n)
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
        msg.position, msg.velocity, msg.effort = q.tolist(), qd.tolist(), effort.tolist()
        self._state_pub.publish(msg)

    def _on_step_error(self, error: Exception) -> None:
        if isinstance(error, SimulationError):
            self.counts["diverged"] += 1
            self.get_logger().warning(str(error), throttle_duration_sec=2.0)
        elif self.context.ok():
            self.counts["step_errors"] += 1
            self.get_logger().error(f"step failed: {error!r}", throttle_duration_sec=2.0)

    def _publish_diagnostics(self) -> None:
        """Step counts; WARN when steps ran late or were skipped, or commands were dropped."""
        self.counts["steps"], self.counts["late_steps"] = self.schedule.steps, self.schedule.late
        self.counts["skipped_steps"] = self.schedule.skipped
        recent = self.counts - self._reported
        self._reported = self.counts.copy()
        status = DiagnosticStatus(name=f"{self.get_name()}: simulation", hardware_id=self.get_fully_qualified_name())
        steps = recent["steps"]
        problems = [] if self.settings is not None else ["waiting for the model (robot_description)"]
        if recent["late_steps"] > WARN_LATE_SHARE * steps or recent["skipped_steps"]:
            problems.append(f"cannot keep real time: {recent['late_steps']} of {steps} steps late, "
                            f"{recent['skipped_steps']} skipped in the last period")
        if recent["dropped"]:
            problems.append(f"{recent['dropped']} effort commands dropped in the last period")
        if recent["diverged"]:
            problems.append("the simulation diverged and was reset")
        command = "no command: zero torque" if self._command_stale else "command held"
        status.level = DiagnosticStatus.WARN if problems else DiagnosticStatus.OK
        status.message = "; ".join(problems) or f"{steps} steps in the last period; {command}"
        status.values = [KeyValue(key=key, value=str(value)) for key, value in sorted(self.counts.items())]
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(msg)


def main(args=None):
    raise SystemExit(run("sim_node", SimNode, args))


if __name__ == "__main__":
    main()
