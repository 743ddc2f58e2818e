"""Record -> identify -> track better, through ROS: sim_node (the true arm, config/true_arm.yaml)
and id_node (computed torque) as their own processes, as `ros2 run` starts them, in lockstep
on simulated time; `excitation`, `record` and `identify` as the commands a user runs.

1. `excitation` writes a short excitation trajectory to a file; sim_node starts at its start.
2. id_node on the report's model drives the arm along it (published on ~/reference) while
   `record --reference /id_node/reference` writes joint_states to a bag, started before the
   motion and stopping by itself TAIL s (simulated) after it, as docs/sim.md says;
   `identify` fits the model to the bag as it is (it trims the rest at both ends itself).
3. The demo's motion (a different one) is tracked by id_node on the report's model, then,
   restarted with --params-file IDENTIFIED.yaml, on the identified one: the tracking error
   RMS falls at least 5x.

A motion starts alike each time: id_node holds the arm at its first point (a one-point
~/reference; its arrival is seen in ~/tracking_error, so the connection is up); for the
demo's motion sim_node is reset there and held still for reset_hold, and the motion's
~/reference is stamped to start when the hold ends (the excitation starts from the hold,
so that the recording holds nothing but physics). Lockstep makes what follows the same
whatever the machine's load: each joint state k+1 is checked to carry (as effort) exactly
the command computed from state k and the reference at state k's simulated time, so no
step went without its command, none had two, and id_node's clock read each state's stamp.
"""

import os
import re
import shlex
import sys
import time

import numpy as np
import pytest
import yaml
from builtin_interfaces.msg import Duration
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from irb140_dynamics.core import irb140, load_model
from irb140_dynamics.core.trajectories.reference import computed_torque
from irb140_dynamics.nodes.demo_node.node import reference_message
from irb140_dynamics.nodes.id_node.settings import DEFAULT_KD, DEFAULT_KP
from irb140_dynamics.ros.messages.joint_messages import JointOrder, read_trajectory

from ..support.node_process import TIMEOUT, interrupt, module_command, run_to_exit, start, wait_for_line
from ..support.paths import ROOT

RATE = 500.0  # Hz of simulated time: the loop, and the recording
PERIOD = round(1e9 / RATE)  # ns
EXCITATION_PERIOD = 5.0  # s
DEMO_PERIOD = 8.0  # s: demo_node's default motion
TRACKED = 4.0  # s of it compared: out to its far end
TAIL = 1.0  # s recorded after the excitation: record's default --tail
ONE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
# s of simulated time (~1 s of wall time) the arm is held still after a reset: the reference arrives meanwhile
HOLD = 2.0
READY = 120.0  # s: processes just started, on two busy cores, until id_node tracks the first hold
SIM = [
    "--params-file",
    str(ROOT / "config" / "true_arm.yaml"),
    "-p",
    "lockstep:=true",
    "-p",
    f"rate:={RATE}",
    "-p",
    "qos.depth:=10000",
]
CONTROLLER = [
    "-p",
    "use_sim_time:=true",
    "-p",
    "qos.depth:=1",
    "-p",
    "effort_commands.enabled:=true",
    "-p",
    "effort_commands.source:=computed_torque",
    "-p",
    "reference_timeout:=0.0",
]


def tool(name: str, *args: str) -> list[str]:
    return [sys.executable, "-m", f"irb140_dynamics.tools.{name}", *args]


def doc_commands() -> dict[str, list[str]]:
    """The excitation, record and identify command lines of docs/sim.md's walkthrough, as
    typed (after `ros2 run irb140_dynamics`): what this test runs."""
    text = (ROOT / "docs" / "sim.md").read_text()
    section = text.split("## Record, identify, track better")[1].split("\n## ")[0]
    commands = {}
    for line in re.sub(r"\\\n\s*", " ", section).splitlines():
        found = re.match(r"\s*ros2 run irb140_dynamics (excitation|record|identify) (.*)", line.split(" #")[0])
        if found:
            commands[found[1]] = shlex.split(found[2])
    assert sorted(commands) == ["excitation", "identify", "record"], commands
    assert "--reference" in commands["record"] and "--ros-args" in commands["record"], commands["record"]
    return commands


def trajectory_message(path) -> JointTrajectory:
    """A JointTrajectory YAML file (as `ros2 topic pub --yaml-file` reads it) as a message."""
    data = yaml.safe_load(path.read_text())
    points = [
        JointTrajectoryPoint(
            positions=p["positions"],
            velocities=p["velocities"],
            accelerations=p["accelerations"],
            time_from_start=Duration(**p["time_from_start"]),
        )
        for p in data["points"]
    ]
    return JointTrajectory(joint_names=data["joint_names"], points=points)


def saw(process, lines: list[str], text: str) -> bool:
    """Has ``process`` printed a line with ``text``? (reads what it printed so far, without waiting)"""
    os.set_blocking(process.stdout.fileno(), False)
    while line := process.stdout.readline():
        lines.append(line)
    return any(text in line for line in lines)


def hold_message(names, positions) -> JointTrajectory:
    zeros = [0.0] * len(positions)
    point = JointTrajectoryPoint(positions=list(positions), velocities=zeros, accelerations=zeros)
    return JointTrajectory(joint_names=list(names), points=[point])


def stamp(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


class Loop:
    """The probe's side of the loop: joint states and tracking errors by stamp (the latest
    of a stamp: sim_node publishes its state again after a ~/reset, with the same stamp),
    the reference, sim_node's parameters and ~/reset."""

    def __init__(self, probe):
        self.probe = probe
        self._subscriptions = []
        self.reference = probe.create_publisher(JointTrajectory, "/id_node/reference", 10)
        self.reset_client = probe.create_client(Trigger, "/sim_node/reset")
        self.parameters = AsyncParameterClient(probe, "sim_node")

    def listen(self, toward) -> None:
        """Joint states and tracking errors from now on, and whether id_node tracks
        ``toward``: new subscriptions, so that nothing queued while the probe did not spin
        (or sent by an id_node stopped since) comes in, and states and errors arrive alike."""
        for subscription in self._subscriptions:
            self.probe.destroy_subscription(subscription)
        self.states, self.errors, self.latest, self.latest_error = {}, {}, -1, -1
        self.toward, self.tracking = list(toward), False
        self._subscriptions = [
            self.probe.create_subscription(JointState, "joint_states", self._on_state, 10000),
            self.probe.create_subscription(JointState, "/id_node/tracking_error", self._on_error, 10000),
        ]

    def _on_state(self, msg: JointState) -> None:
        s = stamp(msg)
        self.states[s], self.latest = msg, max(self.latest, s)
        if not self.tracking and s in self.errors:
            self.tracking = self._toward(msg, self.errors[s])

    def _on_error(self, msg: JointState) -> None:
        s = stamp(msg)
        self.errors[s], self.latest_error = msg, max(self.latest_error, s)
        if not self.tracking and s in self.states:
            self.tracking = self._toward(self.states[s], msg)

    def _toward(self, state: JointState, error: JointState) -> bool:
        """Is ``error`` (reference - position) the error toward ``self.toward``?"""
        return all(abs(q + e - p) <= 1e-12 for q, e, p in zip(state.position, error.position, self.toward, strict=True))

    def send_until(self, msg: JointTrajectory, done, timeout: float = TIMEOUT) -> None:
        """Publish ``msg`` every 50 ms until ``done()`` (a message sent before id_node's end of
        the connection is up is lost; sending it again changes nothing)."""
        sent = [0.0]

        def send():
            if time.monotonic() > sent[0] + 0.05:
                self.reference.publish(msg)
                sent[0] = time.monotonic()

        self.probe.spin_until(done, timeout=timeout, each=send)

    def move(self, msg: JointTrajectory, duration: float, reset: bool = True, also=lambda: True) -> list[int]:
        """Hold the arm at the first point of ``msg``; ``reset``: reset it there, held still
        HOLD s, and follow ``msg`` from the end of the hold (deterministic: the same state at
        the same time), else from HOLD s on; for ``duration`` s: the stamps of those states."""
        pose = list(msg.points[0].positions)
        self.listen(toward=pose)
        self.send_until(hold_message(msg.joint_names, pose), lambda: self.tracking, READY)  # (id_node may be new)
        if reset:
            start = self.reset(pose)
        else:
            start = self.latest + round(HOLD * 1e9)
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(start, 1_000_000_000)
        self.send_until(msg, lambda: self.latest_error >= start and also())
        end = start + round(duration * 1e9)
        self.probe.spin_until(lambda: self.latest >= end, timeout=duration * 4 + TIMEOUT)
        stamps = [s for s in sorted(self.states) if start <= s < end]
        assert len(stamps) == round(duration * RATE), "the probe missed joint states"
        return stamps

    def reset(self, pose) -> int:
        """sim_node reset at ``pose``, held still for HOLD s: when its first step is taken [ns]."""
        values = [Parameter("initial_positions", value=pose), Parameter("reset_hold", value=HOLD)]
        future = self.parameters.set_parameters(values)
        self.probe.spin_until(future.done)
        assert all(result.successful for result in future.result().results)
        assert self.reset_client.wait_for_service(timeout_sec=TIMEOUT)
        future = self.reset_client.call_async(Trigger.Request())
        self.probe.spin_until(future.done)
        reply = future.result()
        assert reply.success, reply.message
        return round(float(re.search(r"held until ([0-9.]+) s", reply.message)[1]) * 1e9)

    def check_lockstep(self, model, msg: JointTrajectory, stamps: list[int]) -> tuple[np.ndarray, int]:
        """The tracking error RMS per joint [rad] over the states ``stamps``; and, checked,
        that each state k+1 carries (as effort) the command id_node computed from state k
        and the reference at its stamp (and published as its tracking error): the count."""
        trajectory = read_trajectory(msg, JointOrder(model.joint_names))
        start = stamp(msg) * 1e-9
        kp, kd = np.full(model.n, DEFAULT_KP), np.full(model.n, DEFAULT_KD)
        errors, checked = [], 0
        for s in stamps:
            state, after = self.states[s], self.states.get(s + PERIOD)
            q, qd = np.array(state.position), np.array(state.velocity)
            q_ref, qd_ref, qdd_ref = trajectory.sample(s * 1e-9 - start)  # as id_node samples
            errors.append(q_ref - q)
            if s in self.errors:  # (id_node's queues are 1 deep: the probe may miss some)
                np.testing.assert_allclose(
                    self.errors[s].position, q_ref - q, rtol=0, atol=1e-12, err_msg=f"reference at {s}"
                )
            if after is not None:
                tau = computed_torque(model, q, qd, q_ref, qd_ref, qdd_ref, kp, kd)
                np.testing.assert_allclose(after.effort, tau, rtol=1e-12, atol=1e-9, err_msg=f"command of {s}")
                checked += 1
        return np.sqrt(np.mean(np.square(errors), axis=0)), checked


@pytest.fixture
def processes():
    running = []

    def launch(command, env=None):
        running.append(start(command, env))
        return running[-1]

    yield launch
    for process in running:
        if process.poll() is None:
            interrupt(process, timeout=5.0)


@pytest.mark.slow
def test_identified_from_a_ros_recording_tracks_five_times_better(probe, processes, tmp_path):  # noqa: F811
    began = time.monotonic()
    excitation_file, bag, identified = tmp_path / "excitation.yaml", tmp_path / "run", tmp_path / "identified.yaml"
    typed = doc_commands()  # the tools' command lines as docs/sim.md gives them, its file names ours
    where = {
        "excitation.yaml": str(excitation_file),
        "run": str(bag),
        "run/": f"{bag}/",
        "identified.yaml": str(identified),
    }
    typed = {name: [where.get(arg, arg) for arg in args] for name, args in typed.items()}
    code, output = run_to_exit(tool("excitation", *typed["excitation"]))
    assert code == 0, output
    excitation = trajectory_message(excitation_file)
    start_pose = list(excitation.points[0].positions)  # where the recording starts: no motion to get there
    sim = processes(
        module_command("irb140_dynamics.nodes.sim_node.node", *SIM, "-p", f"initial_positions:={start_pose}")
    )
    controller = processes(module_command("irb140_dynamics.nodes.id_node.node", *CONTROLLER))
    # as docs/sim.md: record started before the motion, it stops by itself TAIL s after the motion's end
    recorder = processes(tool("record", *typed["record"]))
    loop = Loop(probe)
    lines = []
    assert wait_for_line(recorder, "recording /joint_states (", lines, READY), "".join(lines)  # subscribed
    # the excitation is sent until id_node follows it and record has seen it (its "following" line)
    loop.move(excitation, EXCITATION_PERIOD + TAIL, reset=False, also=lambda: saw(recorder, lines, "following"))
    output, _ = recorder.communicate(timeout=4 * TIMEOUT)
    output = "".join(lines) + output
    assert recorder.returncode == 0 and f"wrote {bag}" in output and "after the end of the motion" in output, output
    # one BLAS thread: OpenBLAS's threads spin for the cores the nodes need (4 s of CPU become 30)
    identify = processes(tool("identify", *typed["identify"]), ONE_THREAD)

    demo = reference_message(DEMO_PERIOD)
    before, checked_before = loop.check_lockstep(irb140(), demo, loop.move(demo, TRACKED))
    output, _ = identify.communicate(timeout=4 * TIMEOUT)
    assert identify.returncode == 0, output
    interrupt(controller)
    processes(module_command("irb140_dynamics.nodes.id_node.node", *CONTROLLER, "--params-file", str(identified)))
    after, checked_after = loop.check_lockstep(load_model(identified), demo, loop.move(demo, TRACKED))
    assert sim.poll() is None

    print(
        f"\ntracking error RMS [mrad], {TRACKED:g} s of the demo motion through ROS, lockstep at {RATE:g} Hz:\n"
        f"  report's model {np.round(before * 1e3, 3).tolist()}\n  identified     {np.round(after * 1e3, 3).tolist()}\n"
        f"  transitions checked {checked_before} + {checked_after}; {time.monotonic() - began:.1f} s in all"
    )
    steps = round(TRACKED * RATE)
    assert checked_before >= steps - 1 and checked_after >= steps - 1
    assert np.sqrt(np.mean(after**2)) * 5 <= np.sqrt(np.mean(before**2))
    assert np.all(after <= before)
