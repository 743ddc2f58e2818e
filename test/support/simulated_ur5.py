"""A simulated public arm for identification tests: the UR5 (test/data/urdf/ur5.urdf) in MuJoCo.

The true arm is the UR5's URDF chain (base_link -> tool0) with viscous friction, Coulomb
friction (MuJoCo's dry friction: a joint at rest is held) and rotor inertia on every
joint, simulated by ``sim.engine.SimulatedArm`` (MuJoCo, from ``sim.mjcf``). A
computed-torque controller on the true model with PD feedback makes it follow a Fourier
excitation; what is recorded is what a driver would publish: the state at each step and
the torque applied during it, with Gaussian noise of ``NOISE`` of each joint's peak. The
prior is the same URDF with each link's mass (and inertia with it) scaled by a factor
within [0.5, 1.5] and no friction.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from irb140_dynamics.core import Friction, RigidBody, RobotModel, rnea_batch
from irb140_dynamics.core.urdf import load_urdf
from irb140_dynamics.identification.excitation import Limits, shaped

from .paths import URDF_DATA

UR5_URDF = URDF_DATA / "ur5.urdf"
BASE, TIP = "base_link", "tool0"
VISCOUS = np.array([2.0, 2.0, 1.5, 0.5, 0.5, 0.3])  # N m s/rad
COULOMB = np.array([3.0, 3.0, 2.0, 0.8, 0.8, 0.5])  # N m
ARMATURE = np.array([0.3, 0.3, 0.15, 0.04, 0.04, 0.02])  # kg m^2
NOISE = 0.005  # of each joint's peak torque
RATE = 500.0  # Hz


def ur5_text() -> str:
    return UR5_URDF.read_text()


def true_ur5() -> RobotModel:
    model = load_urdf(ur5_text(), BASE, TIP).model
    joints = tuple(
        replace(j, friction=Friction(v, c), armature=a) for j, v, c, a in zip(model.joints, VISCOUS, COULOMB, ARMATURE)
    )
    return replace(model, joints=joints)


def prior_ur5(seed: int = 0) -> tuple[RobotModel, np.ndarray]:
    """The UR5's URDF model with link masses off by factors within [0.5, 1.5], no friction."""
    model = load_urdf(ur5_text(), BASE, TIP).model
    factors = np.random.default_rng(seed).uniform(0.5, 1.5, model.n)
    factors[np.argmax(np.abs(factors - 1.0))] = 1.5 if factors[np.argmax(np.abs(factors - 1.0))] > 1.0 else 0.5
    joints = tuple(
        replace(j, link=RigidBody(j.link.mass * f, j.link.com, tuple(f * x for x in j.link.inertia)))
        for j, f in zip(model.joints, factors)
    )
    return replace(model, joints=joints), factors


def excitation(model: RobotModel, seed: int, period: float = 8.0, harmonics: int = 4):
    """A random Fourier trajectory within half the UR5's ranges and speeds (no optimisation)."""
    limits = Limits.of(model, 0.0)
    limits = Limits(np.full(model.n, -2.0), np.full(model.n, 2.0), 0.5 * limits.speed, np.full(model.n, 4.0))
    free = np.random.default_rng(seed).normal(size=2 * model.n * (harmonics - 1))
    return shaped(free, model.n, harmonics, period, limits)


def simulate(arm: RobotModel, trajectory, duration: float, seed: int = 0, stuck=None, noise=NOISE, gains=None):
    """(t, Q, QD, TAU measured) of the MuJoCo arm following ``trajectory`` for ``duration`` s.
    ``stuck``: (joint, t0, t1): that joint's reference held still between t0 and t1;
    ``noise``: of each joint's peak torque; ``gains``: the feedback's scale per joint
    [kg m^2] (default: the UR5's)."""
    from irb140_dynamics.sim.engine import SimulatedArm

    t = np.arange(int(round(duration * RATE))) / RATE
    Q_ref, QD_ref, QDD_ref = trajectory.evaluate(t)
    if stuck is not None:
        joint, t0, t1 = stuck
        held = (t >= t0) & (t < t1)
        Q_ref[held, joint] = trajectory.evaluate([t0])[0][0, joint]
        QD_ref[held, joint] = QDD_ref[held, joint] = 0.0
    feed_forward = rnea_batch(arm, Q_ref, QD_ref, QDD_ref)
    sim = SimulatedArm(arm, period=1.0 / RATE, substeps=2)
    sim.reset(Q_ref[0], QD_ref[0])
    kp, kd = 400.0, 40.0  # 1/s^2, 1/s: through the mass matrix's diagonal scale below
    scale = np.array([5.0, 5.0, 2.0, 0.3, 0.3, 0.1]) if gains is None else np.asarray(gains, dtype=float)
    Q, QD, TAU = (np.empty_like(Q_ref) for _ in range(3))
    for k in range(len(t)):
        q, qd = sim.q, sim.qd
        tau = feed_forward[k] + scale * (kp * (Q_ref[k] - q) + kd * (QD_ref[k] - qd))
        sim.step(tau)
        Q[k], QD[k], TAU[k] = q, qd, sim.applied
    peak = np.abs(TAU).max(axis=0)
    measured = TAU + np.random.default_rng(seed).normal(size=TAU.shape) * noise * peak
    return t, Q, QD, measured


def write_csv(path: Path, names, t, Q, QD, TAU) -> Path:
    columns = (
        ["time"] + [f"position_{n}" for n in names] + [f"velocity_{n}" for n in names] + [f"effort_{n}" for n in names]
    )
    np.savetxt(
        path, np.column_stack([t, Q, QD, TAU]), delimiter=",", header=",".join(columns), comments="", fmt="%.12g"
    )
    return path
