"""Trajectory sampling and computed-torque control (closed loop on our own forward dynamics:
the law's algebra, not the physics, which the MuJoCo tests check)."""

import numpy as np
import pytest

from irb140_dynamics.core import forward_dynamics, irb140
from irb140_dynamics.core.trajectories.reference import Trajectory, computed_torque


def test_sampling_interpolates_and_holds():
    traj = Trajectory(np.array([0.0, 1.0, 3.0]), np.array([[0.0], [1.0], [5.0]]), np.array([[0.0], [2.0], [0.0]]), None)
    for t, q, qd in (
        (-1.0, 0.0, 0.0),
        (0.0, 0.0, 0.0),
        (0.5, 0.5, 1.0),
        (2.0, 3.0, 1.0),
        (3.0, 5.0, 0.0),
        (9.0, 5.0, 0.0),
    ):
        sq, sqd, sqdd = traj.sample(t)
        assert (sq[0], sqd[0]) == pytest.approx((q, qd)) and sqdd is None
    assert traj.duration == 3.0


@pytest.mark.parametrize(
    "times, q",
    [
        ([], np.zeros((0, 1))),
        ([0.0, -1.0], np.zeros((2, 1))),
        ([0.0, np.nan], np.zeros((2, 1))),
        ([0.0, 1.0], np.array([[0.0], [np.inf]])),
        ([0.0, 1.0], np.zeros((3, 1))),
    ],
)
def test_bad_trajectories_are_refused(times, q):
    with pytest.raises(ValueError):
        Trajectory(np.array(times), q, np.zeros_like(q), None)


def test_computed_torque_makes_the_error_a_damped_oscillator():
    model = irb140()
    kp, kd = np.full(6, 400.0), np.full(6, 40.0)
    q_ref = np.array([0.2, -0.4, 0.6, 0.1, 0.5, 0.0])
    q, qd = q_ref + 0.05, np.zeros(6)
    for _ in range(2000):  # 2 s at 1 ms, semi-implicit Euler on our own forward dynamics
        tau = computed_torque(model, q, qd, q_ref, np.zeros(6), None, kp, kd)
        qdd = forward_dynamics(model, q, qd, tau)
        np.testing.assert_allclose(qdd, kp * (q_ref - q) - kd * qd, rtol=1e-9, atol=1e-9)
        qd = qd + 1e-3 * qdd
        q = q + 1e-3 * qd
    np.testing.assert_allclose(q, q_ref, atol=1e-6)
