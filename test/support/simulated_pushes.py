"""An arm at its normal work in MuJoCo, pushed now and then: recordings for the collision
calibration tests.

The arm (its model, friction and rotor inertia included) is stepped by
``sim.engine.SimulatedArm`` at 1 kHz under computed torque (the model's feed-forward along
the reference, PD feedback scaled per joint by the mass matrix's diagonal at the start),
following a random Fourier motion within its limits (``identification.excitation.shaped``:
"normal work", one seed one motion). What is recorded is what a driver publishes, at 500 Hz:
the state at the step's start and the torque applied during it, with Gaussian noise of 1 %
of each joint's torque limit (of its peak torque along the motion where it has none). A
push is a force [N] on the flange origin, base axes, held over [start, end) s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from irb140_dynamics.core import RobotModel
from irb140_dynamics.identification.effort_noise import EffortNoise
from irb140_dynamics.identification.excitation import Limits, shaped

from . import simulated_load

NOISE = EffortNoise(0.01)
PERIOD, HARMONICS = 10.0, 5  # s: the motion's period, and its harmonics


@dataclass(frozen=True)
class Push:
    start: float  # s
    end: float  # s
    force: np.ndarray  # (3,) N, base axes, on the flange origin


def normal_motion(model: RobotModel, seed: int):
    """A random Fourier motion of ``PERIOD`` s within the arm's limits (10 % of each range
    kept free at both ends), at rest at t = 0."""
    free = np.random.default_rng(seed).normal(size=2 * model.n * (HARMONICS - 1))
    return shaped(free, model.n, HARMONICS, PERIOD, Limits.of(model, 0.1))


def run(arm: RobotModel, trajectory, duration: float, seed: int = 0, pushes=()):
    """(t, Q, QD, TAU measured) at 500 Hz of the MuJoCo ``arm`` following ``trajectory``
    for ``duration`` s under computed torque at 1 kHz, pushed as ``pushes`` say, with NOISE
    (``simulated_load.run``: the same loop)."""
    return simulated_load.run(arm, trajectory, duration, NOISE, seed, pushes)


def write_csv(path, names, t, Q, QD, TAU):
    columns = [f"{field}_{name}" for field in ("position", "velocity", "effort") for name in names]
    np.savetxt(path, np.column_stack([t, Q, QD, TAU]), delimiter=",", header=",".join(["time", *columns]), comments="")
    return path
