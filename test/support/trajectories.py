"""What the trajectory tests share: smooth trajectories as a planner sends them, the
controller's playback sampled finer than a re-timing's grid, and the distance of a played
trajectory from its input's path."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from irb140_dynamics.core import Friction, rnea_batch
from irb140_dynamics.core.trajectories import Trajectory
from irb140_dynamics.core.trajectories.interpolation import sample_times, spline


def smooth_trajectory(names, q0, amplitude, points: int = 100, duration: float = 10.0, seed: int = 0) -> Trajectory:
    """Rest to rest along a curved path, with positions, velocities and accelerations at
    every point (the controller interpolates quintic), like a planner's output."""
    rng = np.random.default_rng(seed)
    n = len(names)
    phase, rate = rng.uniform(0, 2 * np.pi, n), rng.uniform(0.5, 1.5, n)
    t = np.linspace(0.0, duration, points)
    w = 2 * np.pi / duration
    s, ds, dds = t - np.sin(w * t) / w, 1 - np.cos(w * t), w * np.sin(w * t)  # rest at both ends
    k = np.pi / duration * rate
    arg = k * s[:, None] + phase
    q = q0 + amplitude * (np.sin(arg) - np.sin(phase))
    qd = amplitude * np.cos(arg) * k * ds[:, None]
    qdd = -amplitude * np.sin(arg) * (k * ds[:, None]) ** 2 + amplitude * np.cos(arg) * k * dds[:, None]
    return Trajectory.of(names, t, q, qd, qdd)


def with_friction(model, viscous: float, coulomb: float, armature: float):
    """The model with the same friction and armature at every joint."""
    joints = tuple(replace(j, friction=Friction(viscous, coulomb), armature=armature) for j in model.joints)
    return replace(model, joints=joints)


def limit_use(model, tr: Trajectory, limits, per_segment: int = 10) -> np.ndarray:
    """value / limit of every torque, velocity and acceleration on ``per_segment`` samples per
    segment of the controller's playback: (samples, 3 n)."""
    sp = spline(tr)
    t, seg = sample_times(sp, per_segment)
    q, qd, qdd = sp.evaluate(t, seg)
    tau = rnea_batch(model, q, qd, qdd)
    with np.errstate(divide="ignore"):
        return np.hstack([np.abs(tau) / limits.torque, np.abs(qd) / limits.velocity, np.abs(qdd) / limits.acceleration])


def path_distance(tr_in: Trajectory, out: Trajectory, sigma_out: np.ndarray, per_segment: int = 10) -> float:
    """The largest distance [rad] of the playback of ``out`` from the path of ``tr_in``, the
    input's own playback (its time from the first point: ``sigma_out`` at out's points):
    each sample's nearest path point by Newton's method from its interval's share of time."""
    path = spline(
        Trajectory(tr_in.joint_names, tr_in.t - tr_in.t[0], tr_in.q, tr_in.qd, tr_in.qdd, tr_in.has_qd, tr_in.has_qdd)
    )
    sp = spline(out)
    t, seg = sample_times(sp, per_segment)
    p = sp.evaluate(t, seg, order=0)[0]
    lo, hi = sigma_out[seg], sigma_out[seg + 1]
    sigma = lo + (t - sp.t0[seg]) / sp.T[seg] * (hi - lo)
    for _ in range(20):
        q, v, a = path.evaluate(sigma)
        r = q - p
        g, h = (r * v).sum(axis=1), (v * v).sum(axis=1) + (r * a).sum(axis=1)
        step = np.where(h > 0, g / np.where(h > 0, h, 1.0), 0.0)
        sigma = np.clip(sigma - step, lo, hi)
    q = path.evaluate(sigma, order=0)[0]
    ends = np.minimum(
        np.linalg.norm(path.evaluate(lo, order=0)[0] - p, axis=1),
        np.linalg.norm(path.evaluate(hi, order=0)[0] - p, axis=1),
    )
    return float(np.minimum(np.linalg.norm(q - p, axis=1), ends).max())
