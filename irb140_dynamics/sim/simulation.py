"""The simulated arm as a drive runs it: what it holds between messages, and when it moves.

Around the engine (``engine.SimulatedArm``) a ``Simulation`` holds the last command
(zero-order hold) until the next, or zero torque once it is older than ``command_timeout``
(0: never); holds the last push on the flange in the same way; and keeps the arm on its
brakes (still, no torque applied) from its start and from each reset until a command has
come since and ``reset_hold`` has passed. A real arm does not move before its controller
commands it: a simulation started before its controller must not fall meanwhile. A
command that goes stale later is no brake: zero torque, and the arm falls, as it does
under a drive whose controller stopped answering.

Times are the caller's, in ns: the node's clock in real time, simulated time in lockstep.
Each method takes ``lock`` (the stepping thread against message callbacks). No ROS here.
"""

from __future__ import annotations

import threading
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from irb140_dynamics.core.model.joint_order import BadMessage
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.sim.engine import SimulatedArm, SimulationError

WARN_LATE_SHARE = 0.01  # a period with more of its steps late than this cannot keep real time


@dataclass(frozen=True, eq=False)
class Setup:
    """What a simulation runs on, built whole (the MuJoCo model compiled) before it is used."""

    engine: SimulatedArm  # fresh: taken over with the state of the one in use when applied
    initial_positions: np.ndarray  # rad: where it starts and each reset puts it
    command_timeout: float  # s: a command (and a push) older than this is let go; 0 = never
    reset_hold: float  # s: braked at least this long after the start and each reset
    position_noise: float = 0.0  # rad, std dev on the positions measured (not on the arm)
    effort_noise: float = 0.0  # N m, std dev on the efforts measured
    joint_names: tuple[str, ...] = field(init=False)

    def __post_init__(self):
        object.__setattr__(self, "joint_names", self.engine.model.joint_names)


@dataclass(frozen=True, eq=False)
class Measured:
    """A state as a driver reports it: q [rad], qd [rad/s], the torque applied [N m], noise added."""

    q: np.ndarray
    qd: np.ndarray
    effort: np.ndarray
    joint_names: tuple[str, ...]


def initial_positions(model: RobotModel, values) -> np.ndarray:
    """The initial positions, or ValueError: one per independent joint (none: zeros), every
    joint within its limits (a mimic joint where it follows its joint)."""
    q = np.zeros(model.n) if values is None or not len(values) else np.array(values, dtype=float)
    if q.shape != (model.n,):
        raise ValueError(f"initial_positions: expected {model.n} values, got {len(q)}")
    for joint, x in zip(model.joints, q if model.mimics is None else model.all_positions(q)):
        lower, upper = joint.position_limits
        if not lower <= x <= upper:
            raise ValueError(f"initial_positions: {joint.name} at {x} rad is outside its limits [{lower}, {upper}]")
    return q


def command_torques(values, n: int) -> np.ndarray:
    """The torques of a command, or BadMessage: n finite numbers."""
    if len(values) != n:
        raise BadMessage("length_mismatch", f"{len(values)} torques for {n} joints")
    tau = np.array(values, dtype=float)
    if not np.isfinite(tau).all():
        raise BadMessage("not_finite", f"torques are not finite: {tau.tolist()}")
    return tau


class Simulation:
    """The arm in use, the command and push it holds, its brakes. ``counts`` (shared with
    the caller's) gains ``resets``, ``command_timeouts``, ``external_wrench.timeouts`` and
    ``diverged``; ``warn(text)`` hears of a blow-up (the engine has reset the arm)."""

    def __init__(self, counts: Counter, warn: Callable[[str], None], seed=None):
        self.counts, self._warn = counts, warn
        self.lock = threading.RLock()
        self.setup: Setup | None = None  # None: no arm yet
        self.arm: SimulatedArm | None = None
        self._command: tuple[int, np.ndarray] | None = None  # (received [ns], tau)
        self._push: tuple[int, np.ndarray, str] | None = None  # (received [ns], wrench, axes)
        self._awaiting = True  # no command since the start or the last reset: braked
        self.held_until = 0  # ns: braked until then at least (reset_hold)
        self._rng = np.random.default_rng(seed)

    def use(self, setup: Setup, now: int) -> bool:
        """Run on ``setup`` from now on: a model of the same joints continues from the
        current state; the first, or other joints, start over at initial_positions
        (braked; the command and push dropped). True when it started over."""
        with self.lock:
            previous, arm = self.setup, self.arm
            fresh = previous is None or setup.joint_names != previous.joint_names
            if fresh or setup.engine.model != arm.model:
                if not fresh:
                    setup.engine.take_state_of(arm)
                self.arm = setup.engine
            self.setup = setup
            if fresh:
                self._command = self._push = None
                self._reset(now)
            return fresh

    def reset(self, now: int) -> bool:
        """The arm back at initial_positions, at rest and braked until a command comes and
        reset_hold has passed (the command held before is dropped); False without an arm."""
        with self.lock:
            if self.arm is None:
                return False
            self._command = None
            self._reset(now)
            return True

    def _reset(self, now: int) -> None:
        self.arm.reset(self.setup.initial_positions)
        self._awaiting = True
        self.held_until = now + round(self.setup.reset_hold * 1e9)
        self.counts["resets"] += 1

    def command(self, tau: np.ndarray, now: int) -> None:
        """Hold ``tau`` (checked, see command_torques) from ``now`` on."""
        with self.lock:
            self._command = (now, tau)
            self._awaiting = False

    def push(self, wrench: np.ndarray, axes: str, now: int) -> None:
        """Hold ``wrench`` (force; torque about the flange origin, in ``axes``: 'base' or
        'tip') on the flange from ``now`` on."""
        with self.lock:
            self._push = (now, wrench, axes)

    def step(self, now: int, tau: np.ndarray | None = None) -> Measured:
        """One period from ``now``: under ``tau`` (lockstep: the command that answers the
        last state, which releases the brakes like any), else under the command held (zero
        torque once stale); none while braked. The state it leaves, measured."""
        with self.lock:
            arm, push = self.arm, self.held_push(now)  # a push goes stale on brakes too
            if tau is None:
                tau = self._held(now)
            else:
                self._awaiting = False
            if self.braked(now):
                arm.applied = np.zeros(arm.n)
            else:
                try:
                    arm.step(tau, *push)
                except SimulationError as error:
                    self.counts["diverged"] += 1
                    self._warn(str(error))
            return self.measure()

    def braked(self, now: int) -> bool:
        return self._awaiting or now < self.held_until

    def _held(self, now: int) -> np.ndarray:
        """The command held while fresh, else zero torque (a timeout counted once)."""
        if self._command is not None:
            received, tau = self._command
            timeout = self.setup.command_timeout
            if not (timeout > 0.0 and now - received > timeout * 1e9):
                return tau
            self._command = None
            self.counts["command_timeouts"] += 1
        return np.zeros(self.arm.n)

    def held_push(self, now: int) -> tuple[np.ndarray | None, str]:
        """(wrench, axes) for a step at ``now``: the one held while fresh, else (None, 'base')."""
        with self.lock:
            if self._push is not None:
                received, wrench, axes = self._push
                timeout = self.setup.command_timeout
                if not (timeout > 0.0 and now - received > timeout * 1e9):
                    return wrench, axes
                self._push = None
                self.counts["external_wrench.timeouts"] += 1
            return None, "base"

    def measure(self) -> Measured:
        """The state now, with the setup's noise on positions and efforts."""
        with self.lock:
            setup, arm = self.setup, self.arm
            q, effort = arm.q, arm.applied.copy()
            if setup.position_noise > 0.0:
                q += self._rng.normal(0.0, setup.position_noise, len(q))
            if setup.effort_noise > 0.0:
                effort += self._rng.normal(0.0, setup.effort_noise, len(q))
            return Measured(q, arm.qd, effort, setup.joint_names)

    def status(self, now: int) -> str:
        """In words, what drives the arm now."""
        with self.lock:
            if self._awaiting:
                return "on brakes until the first command"
            if now < self.held_until:
                return "on brakes (reset_hold)"
            return "command held" if self._command is not None else "no command: zero torque"


def problems(recent: Counter) -> list[str]:
    """What went wrong in a period, from its counts (``steps``, ``late_steps``,
    ``skipped_steps``, ``diverged``, ``<topic>.dropped``, ``<topic>.errors``), in words."""
    found, steps = [], recent["steps"]
    if recent["late_steps"] > WARN_LATE_SHARE * steps or recent["skipped_steps"]:
        late, skipped = recent["late_steps"], recent["skipped_steps"]
        found.append(f"cannot keep real time: {late} of {steps} steps late, {skipped} skipped in the last period")
    dropped = sum(n for key, n in recent.items() if key.endswith((".dropped", ".errors")))
    if dropped:
        found.append(f"{dropped} messages dropped or callbacks failed in the last period")
    if recent["diverged"]:
        found.append("the simulation diverged and was reset")
    return found
