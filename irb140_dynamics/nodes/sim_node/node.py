"""sim_node: a simulated arm (MuJoCo) that takes joint torques and publishes joint states.

Subscribes   effort_commands   std_msgs/Float64MultiArray: joint torques [N m], model joint
                               order (as ros2_control's JointGroupEffortController ~/commands)
             ~/external_wrench geometry_msgs/WrenchStamped: a push on the flange, held (see
                               sim_node.push)
Publishes    joint_states      sensor_msgs/JointState every step: position, velocity, effort =
                               the torque applied, named, stamped
             /clock            rosgraph_msgs/Clock, in lockstep only: the simulated time, every step
             /diagnostics      diagnostic_msgs/DiagnosticArray, 1 Hz: steps, late steps, commands
Serves       ~/reset           std_srvs/Trigger: back to initial_positions, at rest

The true arm is the model of the parameters or of a URDF (``model.source``, as every node's)
and may differ from the model a controller uses. In real time (the default) a command is
held (zero-order hold) until the next; once it is older than command_timeout, zero torque
is applied. The engine steps at ``rate`` in real time (sub-steps allowed) in a thread of
its own, catching up late steps (counted) and skipping when far behind (counted). In
``lockstep`` it steps once per command instead (sim.lockstep), stamps with simulated time
and publishes it on /clock. Bad commands (wrong length, NaN or infinite) are dropped,
counted and warned about, never applied; no exception of ours leaves a callback
(ros.runtime.guard). See docs/sim.md.
"""

from __future__ import annotations

import threading
import time
from collections import Counter

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import WrenchStamped
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock as ClockMessage
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.nodes.sim_node.push import HeldWrench
from irb140_dynamics.nodes.sim_node.settings import NODE_PARAMETERS, SimNodeSettings, build_settings, read_command
from irb140_dynamics.ros.messages.joint_messages import BadMessage
from irb140_dynamics.ros.messages.wrench import chain_links
from irb140_dynamics.ros.parameters.live import Recipe
from irb140_dynamics.ros.parameters.model_source import declare_model_source
from irb140_dynamics.ros.parameters.overrides import NODE_OPTIONS
from irb140_dynamics.ros.parameters.usage import model_sections
from irb140_dynamics.ros.runtime.command_line import Usage
from irb140_dynamics.ros.runtime.guard import Tally, guarded
from irb140_dynamics.ros.runtime.spin import run
from irb140_dynamics.sim.engine import SimulatedArm, SimulationError
from irb140_dynamics.sim.lockstep import TICKS, LockstepClock
from irb140_dynamics.sim.realtime import RealTimeLoop

WARN_LATE_SHARE = 0.01  # /diagnostics WARN when more of the last period's steps were late


def _reset_failed(request, response, error):
    response.success, response.message = False, f"reset failed: {error}"
    return response


class SimNode(Node):
    """The simulated arm: torques in, joint states out, in real time or in lockstep."""

    def __init__(self, **kwargs):
        super().__init__("sim_node", **NODE_OPTIONS, **kwargs)
        self.settings: SimNodeSettings | None = None  # None: waiting for the model (robot_description topic)
        self.arm: SimulatedArm | None = None  # the engine, stepped under self._lock
        self._lock = threading.Lock()  # the arm and settings: the stepping thread against callbacks
        self.tally = Tally(self.get_logger())
        self.counts = self.tally.counts
        self.parameters = declare_model_source(self, Recipe(NODE_PARAMETERS, build_settings))
        self.parameters.on_change(self._use)
        self._reported = Counter()  # the counts at the last diagnostics
        self._command = None  # (time received [s, monotonic], torques)
        self._command_stale = True
        self._rng = np.random.default_rng()
        self._stamp_offset = self.get_clock().now().nanoseconds - time.monotonic_ns()  # node clock - monotonic
        self.last_stamp = 0  # ns, node clock (lockstep: simulated time): of the last state published
        self.reset_stamp = 0  # ns, as last_stamp: states stamped later were stepped after the last reset
        self._held_until = 0  # ns, on self._now(): the arm is held still until then

        depth = self.get_parameter("qos.depth").value
        period = 1.0 / self.get_parameter("rate").value
        self._state_pub = self.create_publisher(JointState, "joint_states", depth)
        commands_qos = QoSProfile(depth=depth, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.create_subscription(Float64MultiArray, "effort_commands", self._on_command, commands_qos)
        self.push = HeldWrench()
        self.create_subscription(WrenchStamped, "~/external_wrench", self._on_wrench, depth)
        self.create_service(Trigger, "~/reset", self._on_reset)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self.create_timer(1.0, self._publish_diagnostics)
        self.lockstep = None
        if self.get_parameter("lockstep").value:
            self.lockstep = LockstepClock(period)
            self._clock_pub = self.create_publisher(ClockMessage, "/clock", QoSProfile(depth=1))
            self._clock_msg = ClockMessage()
            self.create_timer(
                self.get_parameter("lockstep_timeout").value / TICKS,
                self._republish,
                clock=Clock(clock_type=ClockType.STEADY_TIME),
            )
        self.loop = RealTimeLoop(period, self._step, self._on_step_error)
        self.schedule = self.loop.schedule
        if self.parameters.current is not None:
            self._use(self.parameters.current)

    @property
    def model(self) -> RobotModel | None:
        """The RobotModel in force; None while waiting for a URDF."""
        return None if self.settings is None else self.settings.model

    def destroy_node(self):
        self.loop.stop()
        return super().destroy_node()

    def _use(self, settings: SimNodeSettings) -> None:
        """Switch to new settings: a new model of the same joints continues from the current
        state; other joints (a new URDF) start at initial_positions. The first starts the
        loop (lockstep: publishes the first state)."""
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
                self.push.clear()
                self._reset()
        if not first:
            return
        mode = "lockstep: one step per command" if self.lockstep else "real time"
        if self.lockstep:
            self._publish_lockstep()
        else:
            refused = self.loop.start(self.get_parameter("thread_priority").value)
            if refused:
                self.get_logger().warning(f"thread_priority refused ({refused}): ordinary scheduling")
        self.get_logger().info(
            f"ready: {len(names)} joints {names}, {1.0 / self.schedule.period:g} Hz ({mode}), "
            f"payload {settings.model.payload.mass} kg"
        )

    def _now(self) -> int:
        """ns: simulated time (of the state published last) in lockstep, else monotonic."""
        return self.lockstep.stamp if self.lockstep else time.monotonic_ns()

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
        self._held_until = self._now() + round(self.settings.reset_hold * 1e9)
        self.counts["resets"] += 1

    @guarded("reset", fallback=_reset_failed)
    def _on_reset(self, request, response):
        response.success = self.reset()
        if not response.success:
            response.message = "no model yet: waiting for robot_description"
            return response
        response.message = f"reset to {self.settings.initial_positions.tolist()} rad"
        if self.lockstep:  # when the first step is taken (the arm held still until then), exactly
            response.message += f"; held until {self._held_until * 1e-9:.9f} s of simulated time"
        return response

    @guarded("effort_commands")
    def _on_command(self, msg: Float64MultiArray) -> None:
        """Real time: hold the command. Lockstep: apply it for one step, publish the state."""
        self.tally.add("effort_commands", "received")
        arm = self.arm
        if arm is None:
            self.tally.add("effort_commands", "no_model_yet")
            return
        try:
            tau = read_command(msg, arm.n)
        except BadMessage as error:
            self.tally.drop("effort_commands", error)
            return
        if self.lockstep is None:
            self._command = (time.monotonic(), tau)
            self._command_stale = False
            return
        if not self.lockstep.accept(tau):
            return
        with self._lock:
            self._advance(tau)
            self.lockstep.step(tau)
        self._publish_lockstep()

    @guarded("external_wrench")
    def _on_wrench(self, msg: WrenchStamped) -> None:
        """Hold the push from the next step on (see sim_node.push)."""
        self.tally.add("external_wrench", "received")
        if self.arm is None:
            self.tally.add("external_wrench", "no_model_yet")
            return
        try:
            with self._lock:
                self.push.receive(msg, chain_links(self.parameters), self._now())
        except BadMessage as error:
            self.tally.drop("external_wrench", error)

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

    def _advance(self, tau: np.ndarray) -> None:
        """One step under tau (under the lock), or none while held after a reset; a blow-up
        (the engine resets the arm) is counted."""
        arm = self.arm
        if self._now() < self._held_until:
            arm.applied = np.zeros(arm.n)
            return
        try:
            arm.step(tau, *self.push.current(self._now(), self.settings.command_timeout))
        except SimulationError as error:
            self.counts["diverged"] += 1
            self.tally.warn("simulation", str(error))

    def _step(self, k: int, t: float) -> None:
        """Step k of the stepping thread (real time), due at t (monotonic): apply the held
        command for one period, then publish the state."""
        if not self.context.ok():
            return
        with self._lock:
            self._advance(self._held_command(time.monotonic()))
            self.last_stamp = self._stamp_offset + round(t * 1e9)  # node clock, ns
            state = self._state()
        self._publish_state(*state)

    def _state(self):
        arm = self.arm
        return arm.q, arm.qd, arm.applied, self._state_msg, self.settings, self.last_stamp

    def _publish_state(self, q, qd, effort, msg, settings, stamp) -> None:
        if settings.position_noise > 0.0:
            q += self._rng.normal(0.0, settings.position_noise, len(q))
        if settings.effort_noise > 0.0:
            effort = effort + self._rng.normal(0.0, settings.effort_noise, len(q))
        if not (np.isfinite(q).all() and np.isfinite(qd).all() and np.isfinite(effort).all()):
            self.tally.drop("joint_states", BadMessage("not_finite", "a state that is not finite was not published"))
            return
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
        msg.position, msg.velocity, msg.effort = q.tolist(), qd.tolist(), effort.tolist()
        self._state_pub.publish(msg)

    def _publish_lockstep(self) -> None:
        """Lockstep: /clock, then the state, both at the current simulated time."""
        if not self.context.ok():  # shutting down (Ctrl-C): a command still came in
            return
        with self._lock:
            self.last_stamp = self.lockstep.stamp
            state = self._state()
        clock = self._clock_msg.clock
        clock.sec, clock.nanosec = divmod(self.last_stamp, 1_000_000_000)
        self._clock_pub.publish(self._clock_msg)
        self._publish_state(*state)

    @guarded("joint_states")
    def _republish(self) -> None:
        """Lockstep, no command for lockstep_timeout: the last state (and /clock) again."""
        if self.arm is not None and self.lockstep.tick():
            self._publish_lockstep()

    def _on_step_error(self, error: Exception) -> None:
        if self.context.ok():
            self.tally.error("steps", error)

    @guarded("diagnostics")
    def _publish_diagnostics(self) -> None:
        """Step counts; WARN when steps ran late or were skipped, or commands were dropped."""
        if self.lockstep:
            self.counts["steps"], self.counts["republished"] = self.lockstep.steps, self.lockstep.republished
            self.counts["duplicates_dropped"] = self.lockstep.duplicates
        if self.push.timed_out:
            self.counts["external_wrench.timeouts"] = self.push.timed_out
        else:
            self.counts["steps"], self.counts["late_steps"] = self.schedule.steps, self.schedule.late
            self.counts["skipped_steps"] = self.schedule.skipped
        recent = self.counts - self._reported
        self._reported = self.counts.copy()
        hardware_id = self.parameters.robot_name or self.get_fully_qualified_name()
        status = DiagnosticStatus(name=f"{self.get_name()}: simulation", hardware_id=hardware_id)
        steps = recent["steps"]
        problems = [] if self.settings is not None else ["waiting for the model (robot_description)"]
        if recent["late_steps"] > WARN_LATE_SHARE * steps or recent["skipped_steps"]:
            problems.append(
                f"cannot keep real time: {recent['late_steps']} of {steps} steps late, "
                f"{recent['skipped_steps']} skipped in the last period"
            )
        dropped = sum(n for key, n in recent.items() if key.endswith((".dropped", ".errors")))
        if dropped:
            problems.append(f"{dropped} messages dropped or callbacks failed in the last period")
        if recent["diverged"]:
            problems.append("the simulation diverged and was reset")
        if self.lockstep:
            state = f"lockstep, {recent['republished']} states republished (no command)"
        else:
            state = "no command: zero torque" if self._command_stale else "command held"
        status.level = DiagnosticStatus.WARN if problems else DiagnosticStatus.OK
        status.message = "; ".join(problems) or f"{steps} steps in the last period; {state}"
        status.values = [KeyValue(key=key, value=str(value)) for key, value in sorted(self.counts.items())]
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(msg)


def usage() -> Usage:
    """What ``sim_node --help`` prints: this module's docstring and every parameter."""
    return Usage("sim_node", __doc__, [*model_sections(), ("sim_node's own", NODE_PARAMETERS)])


def main(args=None):
    raise SystemExit(run("sim_node", SimNode, args, usage=usage))


if __name__ == "__main__":
    main()
