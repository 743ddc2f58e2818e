"""The true arm: a RobotModel simulated by MuJoCo, stepped at a fixed period under held torques.

The physics is MuJoCo's (see ``mjcf``): the model's inertials, armature, viscous friction
(damping), Coulomb friction (MuJoCo's dry friction, frictionloss) and position limits
(soft stops). A step holds the applied torques for one period, integrated in ``substeps``
MuJoCo steps. Torques beyond a joint's torque_limit (when it has one, > 0) are clipped to
it: the drives saturate, and ``applied`` says what was applied.

A wrench on the flange (force [N]; torque [N m] about the flange origin, in the base's axes
or the flange's) can be applied with a step: MuJoCo's ``xfrc_applied`` takes the force and
the torque about the body's centre of mass (``xipos``) in world axes, so the torque is
moved there, m_com = m + (p_flange - p_com) x f, at the pose of each sub-step.
"""

from __future__ import annotations

import logging
import math
import time

import mujoco
import numpy as np

from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.sim.mjcf import mujoco_model

# 4th order: at 1 kHz a 0.5 s free fall of the IRB-140 through 2.7 rad stays within 1e-8 rad of
# the exact motion, where implicitfast (first order) is 2e-2 rad off (step costs: docs/benchmarks.md).
DEFAULT_INTEGRATOR = "RK4"


class SimulationError(RuntimeError):
    """The simulation blew up (non-finite or absurd state); the arm has been reset."""


class SimulatedArm:
    """One arm in MuJoCo: reset, apply torques, step, read q, qd and the applied torques."""

    def __init__(
        self, model: RobotModel, period: float = 0.001, substeps: int = 1, integrator: str = DEFAULT_INTEGRATOR
    ):
        if not (math.isfinite(period) and period > 0.0):
            raise ValueError(f"period: must be > 0, got {period}")
        if int(substeps) != substeps or substeps < 1:
            raise ValueError(f"substeps: must be an integer >= 1, got {substeps}")
        if mujoco.get_mju_user_warning() is None:  # else MuJoCo prints and writes MUJOCO_LOG.TXT
            mujoco.set_mju_user_warning(_log_warning)
        self.model, self.period, self.substeps = model, period, int(substeps)
        self.mj_model = mujoco_model(model, timestep=period / self.substeps, integrator=integrator)
        self.mj_model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET  # we reset, and say so
        self.data = mujoco.MjData(self.mj_model)
        limits = np.array(model.torque_limits, dtype=float)
        self.torque_limits = np.where(limits > 0.0, limits, np.inf)
        self.applied = np.zeros(model.n)
        # the state's coordinates in MuJoCo's qpos/qvel: every joint, or the independent ones (mimic joints)
        self._dofs = slice(None) if model.mimics is None else np.array(model.independent)
        self._flange_body = mujoco.mj_name2id(self.mj_model, mujoco.mjtObj.mjOBJ_BODY, model.joints[model.carrier].name)
        self._flange = model.flange.matrix()  # the flange in its link's frame (model.carrier's)
        self._reset_state = (np.zeros(model.n), np.zeros(model.n))
        self.reset(np.zeros(model.n))

    @property
    def n(self) -> int:
        return self.model.n

    @property
    def q(self) -> np.ndarray:
        """Joint positions [rad] (a copy; the independent joints': the state's)."""
        return self.data.qpos[self._dofs].copy()

    @property
    def qd(self) -> np.ndarray:
        """Joint velocities [rad/s] (a copy; the independent joints')."""
        return self.data.qvel[self._dofs].copy()

    @property
    def time(self) -> float:
        """Simulated time since the last reset [s]."""
        return float(self.data.time)

    def reset(self, q, qd=None) -> None:
        """Put the arm at q (and qd, default at rest), time 0, no torque applied."""
        q = self._checked("q", q)
        qd = np.zeros(self.n) if qd is None else self._checked("qd", qd)
        mujoco.mj_resetData(self.mj_model, self.data)
        self._set(q, qd, 0.0)
        self._reset_state = (q, qd)

    def take_state_of(self, other: SimulatedArm) -> None:
        """Continue from another arm's state (a model change while running)."""
        self._set(other.q, other.qd, other.data.time)
        self.applied = other.applied.copy()
        self._reset_state = other._reset_state

    def step(self, tau, wrench=None, frame: str = "base") -> None:
        """Apply tau [N m] (clipped to the torque limits) for one period, and ``wrench`` (6
        finite numbers: force; torque about the flange origin, in the axes of ``frame``,
        ``base`` or ``tip``) on the flange if given.

        Raises SimulationError, with the arm reset to where it was last reset, if the state
        stops being finite (torques far beyond anything the arm can take).
        """
        self.applied = np.clip(self._checked("tau", tau), -self.torque_limits, self.torque_limits)
        if wrench is not None:
            wrench = np.asarray(wrench, dtype=float)
            if wrench.shape != (6,) or not np.isfinite(wrench).all() or frame not in ("base", "tip"):
                raise ValueError(f"wrench: expected 6 finite numbers in 'base' or 'tip' axes, got {wrench}, {frame!r}")
        data = self.data
        data.qfrc_applied[self._dofs] = self.applied  # a mimic joint's: none (its equality carries it)
        for _ in range(self.substeps):
            data.xfrc_applied[self._flange_body] = 0.0 if wrench is None else self._at_com(wrench, frame)
            mujoco.mj_step(self.mj_model, data)
        data.xfrc_applied[self._flange_body] = 0.0
        if not (np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()) or self._diverged():
            self.reset(*self._reset_state)
            raise SimulationError("the simulation diverged (non-finite state); the arm was reset")

    def follow(self, feed_forward, Q_ref, QD_ref, stiffness, damping) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Q, QD, TAU), each (N, n): a drive's computed-torque loop at the arm's period, one
        step per row of the (N, n) references: at each step's start the state (q, qd) is read
        and tau = feed_forward + stiffness (q_ref - q) + damping (qd_ref - qd) (per joint,
        (n,) gains) is applied for the period, clipped to the torque limits; TAU is what was
        applied. The same physics as ``step`` N times, without its per-step checks (the
        loop of a long recording): the state is checked finite at the end (SimulationError
        and the arm reset, as ``step``)."""
        feed_forward, Q_ref, QD_ref = (np.asarray(x, dtype=float) for x in (feed_forward, Q_ref, QD_ref))
        if not feed_forward.shape == Q_ref.shape == QD_ref.shape or feed_forward.shape[1:] != (self.n,):
            raise ValueError(
                f"references: expected three (N, {self.n}) arrays, got {feed_forward.shape}, "
                f"{Q_ref.shape}, {QD_ref.shape}"
            )
        stiffness, damping = np.asarray(stiffness, dtype=float), np.asarray(damping, dtype=float)
        Q, QD, TAU = (np.empty_like(feed_forward) for _ in range(3))
        data, mj_model, low, high = self.data, self.mj_model, -self.torque_limits, self.torque_limits
        qpos, qvel, applied, dofs = data.qpos, data.qvel, data.qfrc_applied, self._dofs
        for k in range(len(feed_forward)):
            Q[k], QD[k] = qpos[dofs], qvel[dofs]
            tau = feed_forward[k] + stiffness * (Q_ref[k] - Q[k]) + damping * (QD_ref[k] - QD[k])
            np.clip(tau, low, high, out=TAU[k])
            applied[dofs] = TAU[k]
            for _ in range(self.substeps):
                mujoco.mj_step(mj_model, data)
        if len(TAU):
            self.applied = TAU[-1].copy()
        if not (np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()) or self._diverged():
            self.reset(*self._reset_state)
            raise SimulationError("the simulation diverged (non-finite state); the arm was reset")
        return Q, QD, TAU

    def flange_pose(self) -> np.ndarray:
        """The flange's pose in the base frame as MuJoCo has it at the current state, 4x4."""
        body = np.eye(4)
        body[:3, :3] = self.data.xmat[self._flange_body].reshape(3, 3)
        body[:3, 3] = self.data.xpos[self._flange_body]
        return body @ self._flange

    def _at_com(self, wrench: np.ndarray, frame: str) -> np.ndarray:
        """The flange wrench as xfrc_applied wants it: world axes, torque about the body's
        centre of mass, at the current pose (kinematics computed first)."""
        mujoco.mj_kinematics(self.mj_model, self.data)
        pose = self.flange_pose()
        force, torque = wrench[:3], wrench[3:]
        if frame == "tip":
            force, torque = pose[:3, :3] @ force, pose[:3, :3] @ torque
        lever = pose[:3, 3] - self.data.xipos[self._flange_body]
        return np.concatenate([force, torque + np.cross(lever, force)])

    def _diverged(self) -> bool:
        return data_warning(self.data, mujoco.mjtWarning.mjWARN_BADQACC) > 0

    def _set(self, q, qd, time: float) -> None:
        mimics = self.model.mimics is not None  # then every joint placed as the state's ones say
        self.data.qpos[:] = self.model.all_positions(q) if mimics else q
        self.data.qvel[:] = self.model.mimic_matrix() @ qd if mimics else qd
        self.data.time = time
        self.data.qfrc_applied[:] = 0.0
        self.applied = np.zeros(self.n)
        for warning in self.data.warning:
            warning.number = 0
        mujoco.mj_forward(self.mj_model, self.data)

    def _checked(self, name: str, values) -> np.ndarray:
        x = np.asarray(values, dtype=float)
        if x.shape != (self.n,):
            raise ValueError(f"{name}: expected {self.n} values, got shape {x.shape}")
        if not np.isfinite(x).all():
            raise ValueError(f"{name}: must be finite, got {x.tolist()}")
        return x.copy()


WARNING_PERIOD = 2.0  # s: MuJoCo's warnings are logged at most once per period (a model it
# cannot step stably warns on every step); those held back are counted in the next
_warnings = {"next": 0.0, "held": 0}


def _log_warning(message: str) -> None:
    now = time.monotonic()
    if now < _warnings["next"]:
        _warnings["held"] += 1
        return
    held = f" (and {_warnings['held']} more since the last)" if _warnings["held"] else ""
    _warnings["next"], _warnings["held"] = now + WARNING_PERIOD, 0
    logging.getLogger(__name__).warning("MuJoCo: %s%s", message, held)


def data_warning(data: mujoco.MjData, kind) -> int:
    """How many times MuJoCo raised a warning of ``kind`` since the counters were cleared."""
    return int(data.warning[int(kind)].number)
