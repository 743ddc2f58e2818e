"""A load identification run on a simulated arm, as a user makes it on a real one.

The true arm (its model with friction and rotor inertia, the payload attached) is stepped in
MuJoCo (``sim.engine.SimulatedArm``) at 1 kHz by a computed-torque controller: the feed-forward
of the true arm along the reference, PD feedback scaled per joint by the mass matrix's
diagonal at the start. What is recorded is what a driver publishes, at 500 Hz: the state at
the step's start and the torque MuJoCo applied during it, with Gaussian noise of the stated
``EffortNoise`` (1 % of each joint's torque limit, of its peak torque where it has none).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.spatial.transform import Rotation

from irb140_dynamics.core import Friction, RigidBody, RobotModel, mass_matrix, rnea_batch
from irb140_dynamics.identification.effort_noise import EffortNoise

from .simulated_ur5 import write_csv  # noqa: F401  (the loads' recordings as the UR5's: one writer)

CONTROL_RATE = 1000.0  # Hz
RECORD_EVERY = 2  # control steps per recorded sample: 500 Hz
KP, KD = 400.0, 40.0  # 1/s^2, 1/s: the feedback's bandwidth, through the mass matrix's diagonal


def tool(mass, com, moments, angles) -> RigidBody:
    """A payload of principal moments ``moments`` [kg m^2] turned by ``angles`` (xyz Euler, rad)."""
    R = Rotation.from_euler("xyz", angles).as_matrix()
    I = R @ np.diag(moments) @ R.T
    return RigidBody(mass, com, (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]))


def with_drive_losses(model: RobotModel) -> RobotModel:
    """The model with viscous and Coulomb friction and rotor inertia on every joint, sized by
    its torque limit (a URDF gives none): 0.5 % of the limit per rad/s, 1 % of it, and
    0.1 % of it in kg m^2."""
    limits = np.array(model.torque_limits, dtype=float)
    joints = tuple(
        replace(j, friction=Friction(0.005 * limit, 0.01 * limit), armature=0.001 * limit)
        for j, limit in zip(model.joints, limits)
    )
    return replace(model, joints=joints)


def run(arm: RobotModel, trajectory, duration: float, noise: EffortNoise, seed: int = 0, pushes=()):
    """(t, Q, QD, TAU measured) at 500 Hz of the MuJoCo ``arm`` (payload included) following
    ``trajectory`` for ``duration`` s under computed torque at 1 kHz; ``pushes``: forces on
    the flange origin, base axes, each held over [start, end) s (``simulated_pushes.Push``)."""
    from irb140_dynamics.sim.engine import SimulatedArm

    steps = int(round(duration * CONTROL_RATE))
    t = np.arange(steps) / CONTROL_RATE
    Q_ref, QD_ref, QDD_ref = trajectory.evaluate(t)
    feed_forward = rnea_batch(arm, Q_ref, QD_ref, QDD_ref)
    scale = np.diag(mass_matrix(arm, Q_ref[0])) + np.array([j.armature for j in arm.joints])
    sim = SimulatedArm(arm, period=1.0 / CONTROL_RATE)
    sim.reset(Q_ref[0], QD_ref[0])
    kp, kd = scale * KP, scale * KD
    forces = [next((p.force for p in pushes if p.start <= tk < p.end), None) for tk in t]
    pushed = np.flatnonzero([force is not None for force in forces])
    Q, QD, TAU = (np.empty((steps, arm.n)) for _ in range(3))
    k = 0
    while k < steps:  # the steps unpushed in one call each (SimulatedArm.follow: step's physics)
        following = np.searchsorted(pushed, k)
        end = int(pushed[following]) if following < len(pushed) else steps
        if end > k:
            Q[k:end], QD[k:end], TAU[k:end] = sim.follow(feed_forward[k:end], Q_ref[k:end], QD_ref[k:end], kp, kd)
            k = end
            continue
        Q[k], QD[k] = sim.q, sim.qd
        sim.step(feed_forward[k] + kp * (Q_ref[k] - Q[k]) + kd * (QD_ref[k] - QD[k]), [*forces[k], 0.0, 0.0, 0.0])
        TAU[k] = sim.applied
        k += 1
    Q, QD, TAU = Q[::RECORD_EVERY], QD[::RECORD_EVERY], TAU[::RECORD_EVERY]
    sigma = noise.sigma(arm, np.abs(TAU).max(axis=0))
    measured = TAU + np.random.default_rng(seed).normal(size=TAU.shape) * sigma
    return t[::RECORD_EVERY], Q, QD, measured
