"""sim_node: a simulated arm (MuJoCo) that takes joint torques and publishes joint states.

Subscribes   effort_commands   std_msgs/Float64MultiArray: joint torques [N m], model joint
                               order (as ros2_control's JointGroupEffortController ~/commands)
             ~/external_wrench geometry_msgs/WrenchStamped: a push on the flange, in the axes of
                               the tip link (flange) or the base link its frame_id names
Publishes    joint_states      sensor_msgs/JointState every step: position, velocity, effort =
                               the torque applied, named, stamped
             /clock            rosgraph_msgs/Clock, in lockstep only: the simulated time, every step
             /diagnostics      diagnostic_msgs/DiagnosticArray, 1 Hz: steps, late steps, commands
Serves       ~/reset           std_srvs/Trigger: back to initial_positions, at rest, on brakes

The true arm is the model of the parameters or of a URDF (``model.source``, as every node's).
It stays on its brakes from startup and each reset until its first command (and reset_hold);
commands and pushes are held, and let go after command_timeout (sim.simulation). It steps at
``rate`` in real time in a thread of its own (sim.realtime), or in ``lockstep`` once per
command on simulated time, published on /clock (sim.lockstep). Bad messages are dropped,
counted and warned about; no exception of ours leaves a callback (ros.runtime.guard); docs/sim.md.
"""

from __future__ import annotations

import time

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock as ClockMessage
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, String
from std_srvs.srv import Trigger

from irb140_dynamics.node_help import Usage
from irb140_dynamics.nodes.sim_node.settings import NODE_PARAMETERS, build_setup
from irb140_dynamics.ros.messages.joint_messages import BadMessage
from irb140_dynamics.ros.messages.wrench import chain_links, read_wrench
from irb140_dynamics.ros.parameters.arm import DESCRIPTION_QOS, ArmParameters
from irb140_dynamics.ros.parameters.overrides import NODE_OPTIONS
from irb140_dynamics.ros.parameters.usage import model_sections
from irb140_dynamics.ros.runtime.guard import Tally, guarded
from irb140_dynamics.ros.runtime.rebuild import Rebuild
from irb140_dynamics.ros.runtime.spin import run
from irb140_dynamics.sim.lockstep import TICKS, LockstepClock
from irb140_dynamics.sim.realtime import RealTimeLoop
from irb140_dynamics.sim.simulation import Measured, Setup, Simulation, command_torques, problems


def _reset_failed(request, response, error):
    response.success, response.message = False, f"reset failed: {error}"
    return response


class SimNode(Node):
    """The simulated arm: torques in, joint states out, in real time or in lockstep."""

    def __init__(self, **kwargs):
        super().__init__("sim_node", **NODE_OPTIONS, **kwargs)
        self.tally = Tally(self.get_logger())
        self.counts = self.tally.counts
        self._reported = self.counts.copy()  # the counts at the last diagnostics
        self.simulation = Simulation(self.counts, lambda text: self.tally.warn("simulation", text))
        self.parameters = ArmParameters(self, NODE_PARAMETERS)
        self._reader = Rebuild(self, self.parameters.read_topic, self._take_urdf)
        self._draft = None  # the setup of a change accepted by _on_set, for _on_set_done
        self._stamp_offset = self.get_clock().now().nanoseconds - time.monotonic_ns()  # node clock - monotonic
        self.last_stamp = 0  # ns, node clock (lockstep: simulated time): of the last state published
        self.reset_stamp = 0  # ns, as last_stamp: states stamped later were stepped after the last reset
        self._names, self._state_msg = (), JointState()

        depth = self.get_parameter("qos.depth").value
        period = 1.0 / self.get_parameter("rate").value
        self._state_pub = self.create_publisher(JointState, "joint_states", depth)
        commands_qos = QoSProfile(depth=depth, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.create_subscription(Float64MultiArray, "effort_commands", self._on_command, commands_qos)
        self.create_subscription(WrenchStamped, "~/external_wrench", self._on_wrench, depth)
        self.create_service(Trigger, "~/reset", self._on_reset)
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self.create_timer(1.0, self._publish_diagnostics)
        self.lockstep = None
        if self.get_parameter("lockstep").value:
            self.lockstep = LockstepClock(period)
            self._clock_pub = self.create_publisher(ClockMessage, "/clock", QoSProfile(depth=1))
            steady = Clock(clock_type=ClockType.STEADY_TIME)
            self.create_timer(self.get_parameter("lockstep_timeout").value / TICKS, self._republish, clock=steady)
        self.loop = RealTimeLoop(period, self._step, self._on_step_error)
        first = self.parameters.draft(build_setup, self.parameters.values())
        if first is not None:
            self._use(first)
        self.add_on_set_parameters_callback(self._on_set)
        self.add_post_set_parameters_callback(self._on_set_done)
        if self.parameters.from_topic:
            self.create_subscription(String, "robot_description", self._on_description, DESCRIPTION_QOS)

    @property
    def model(self):
        """The model in force (None while waiting for a URDF)."""
        return None if self.simulation.arm is None else self.simulation.arm.model

    def _on_set(self, parameters) -> SetParametersResult:
        """A change is accepted only if the whole new configuration checks (the engine built)."""
        result, self._draft = self.parameters.check_change(parameters, build_setup)
        return result

    def _on_set_done(self, parameters) -> None:
        draft, self._draft = self._draft, None
        if draft is not None:
            self._use(draft)

    def _on_description(self, msg: String) -> None:
        """A new URDF: read off the executor, then checked (``_take_urdf``)."""
        self._reader.submit(msg.data)

    def _take_urdf(self, urdf) -> None:
        """The URDF read: checked whole (its engine built), swapped in, or refused."""
        draft = self.parameters.take_urdf(urdf, build_setup)
        if draft is not None:
            self._use(draft)

    def destroy_node(self):
        self.loop.stop()
        return super().destroy_node()

    def _use(self, setup: Setup) -> None:
        """Run on ``setup``; the first starts stepping (lockstep: publishes the first state)."""
        first = self.simulation.setup is None
        with self.simulation.lock:
            if self.simulation.use(setup, self._now()):
                self.reset_stamp = self.last_stamp
        if not first:
            return
        if self.lockstep:
            self._publish_lockstep(self.simulation.measure())
        else:
            refused = self.loop.start(self.get_parameter("thread_priority").value)
            if refused:
                self.get_logger().warning(f"thread_priority refused ({refused}): ordinary scheduling")
        mode = "lockstep: one step per command" if self.lockstep else "real time"
        self.get_logger().info(
            f"ready: {len(setup.joint_names)} joints {list(setup.joint_names)}, {1.0 / self.loop.schedule.period:g} Hz "
            f"({mode}), payload {setup.engine.model.payload.mass} kg; on brakes until the first command"
        )

    def _now(self) -> int:
        """ns: simulated time (of the state published last) in lockstep, else the node's clock."""
        return self.lockstep.stamp if self.lockstep else self._stamp_offset + time.monotonic_ns()

    def reset(self) -> bool:
        """The arm back at initial_positions, at rest, on brakes (see sim.simulation); False without a model."""
        with self.simulation.lock:
            self.reset_stamp = self.last_stamp
            return self.simulation.reset(self._now())

    @guarded("reset", fallback=_reset_failed)
    def _on_reset(self, request, response):
        response.success = self.reset()
        if not response.success:
            response.message = "no model yet: waiting for robot_description"
            return response
        setup, held = self.simulation.setup, self.simulation.held_until * 1e-9
        response.message = f"reset to {setup.initial_positions.tolist()} rad; on brakes until the next command"
        if self.lockstep:  # the first step taken, exactly: a reference stamped so starts with it
            response.message += f"; held until {held:.9f} s of simulated time"
        return response

    @guarded("effort_commands")
    def _on_command(self, msg: Float64MultiArray) -> None:
        """Real time: hold the command. Lockstep: apply it for one step, publish the state."""
        self.tally.add("effort_commands", "received")
        arm = self.simulation.arm
        if arm is None:
            self.tally.add("effort_commands", "no_model_yet")
            return
        try:
            tau = command_torques(msg.data, arm.n)
        except BadMessage as error:
            self.tally.drop("effort_commands", error)
            return
        if self.lockstep is None:
            self.simulation.command(tau, self._now())
        elif self.lockstep.accept(tau):
            state = self.simulation.step(self.lockstep.stamp, tau)
            self.lockstep.step(tau)
            self._publish_lockstep(state)

    @guarded("external_wrench")
    def _on_wrench(self, msg: WrenchStamped) -> None:
        """Hold the push from the next step on (ros.messages.wrench reads it)."""
        self.tally.add("external_wrench", "received")
        if self.simulation.arm is None:
            self.tally.add("external_wrench", "no_model_yet")
            return
        try:
            self.simulation.push(*read_wrench(msg, chain_links(self.parameters)), self._now())
        except BadMessage as error:
            self.tally.drop("external_wrench", error)

    def _step(self, k: int, t: float) -> None:
        """Step k of the stepping thread (real time), due at t (monotonic): stepped, published."""
        if not self.context.ok():
            return
        stamp = self._stamp_offset + round(t * 1e9)
        with self.simulation.lock:
            state = self.simulation.step(stamp)
            self.last_stamp = stamp
        self._publish_state(state, stamp)

    def _publish_state(self, state: Measured, stamp: int) -> None:
        if not (np.isfinite(state.q).all() and np.isfinite(state.qd).all() and np.isfinite(state.effort).all()):
            self.tally.drop("joint_states", BadMessage("not_finite", "a state that is not finite was not published"))
            return
        if state.joint_names is not self._names:
            self._names, self._state_msg = state.joint_names, JointState(name=list(state.joint_names))
        msg = self._state_msg
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
        msg.position, msg.velocity, msg.effort = state.q.tolist(), state.qd.tolist(), state.effort.tolist()
        self._state_pub.publish(msg)

    def _publish_lockstep(self, state: Measured) -> None:
        """Lockstep: /clock, then the state, both at the current simulated time."""
        if not self.context.ok():  # shutting down (Ctrl-C): a command still came in
            return
        self.last_stamp = stamp = self.lockstep.stamp
        clock = ClockMessage()
        clock.clock.sec, clock.clock.nanosec = divmod(stamp, 1_000_000_000)
        self._clock_pub.publish(clock)
        self._publish_state(state, stamp)

    @guarded("joint_states")
    def _republish(self) -> None:
        """Lockstep, no command for lockstep_timeout: the last state (and /clock) again."""
        if self.simulation.arm is not None and self.lockstep.tick():
            self._publish_lockstep(self.simulation.measure())

    def _on_step_error(self, error: Exception) -> None:
        if self.context.ok():
            self.tally.error("steps", error)

    @guarded("diagnostics")
    def _publish_diagnostics(self) -> None:
        """The counts since startup; WARN with every problem of the last period (sim.simulation.problems)."""
        counts, simulation = self.counts, self.simulation
        for key, value in (self.lockstep or self.loop.schedule).counts().items():  # set, not added
            counts[key] = value
        recent, self._reported = counts - self._reported, counts.copy()
        found = problems(recent) if simulation.arm is not None else ["waiting for the model (robot_description)"]
        state = "no model" if simulation.arm is None else simulation.status(self._now())
        if self.lockstep:
            state = f"lockstep, {recent['republished']} states republished (no command); {state}"
        status = DiagnosticStatus(
            name=f"{self.get_name()}: simulation",
            hardware_id=self.parameters.robot_name or self.get_fully_qualified_name(),
            level=DiagnosticStatus.WARN if found else DiagnosticStatus.OK,
            message="; ".join(found) or f"{recent['steps']} steps in the last period; {state}",
            values=[KeyValue(key=key, value=str(value)) for key, value in sorted(counts.items())],
        )
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(msg)


def usage() -> Usage:
    """What ``sim_node --help`` prints: this module's docstring and every parameter."""
    return Usage("sim_node", __doc__, [*model_sections(), ("sim_node's own", NODE_PARAMETERS)])


def main(args=None):
    raise SystemExit(run("sim_node", SimNode, args, usage=usage))
