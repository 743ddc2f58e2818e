"""The velocity differentiator: exact on ramps, a first-order low-pass on steps."""

import math

import numpy as np
import pytest

from irb140_dynamics.core.monitoring.filters import VelocityDifferentiator


def test_converges_to_the_slope_of_a_velocity_ramp():
    qdd = np.array([1.0, -2.0, 0.5])
    f = VelocityDifferentiator(3, cutoff_hz=20.0)
    for k in range(200):
        t = 0.001 * k
        estimate = f.update(t, qdd * t)
    np.testing.assert_allclose(estimate, qdd, rtol=1e-9)


def test_step_response_is_first_order_with_the_cutoff_time_constant():
    fc, dt = 5.0, 0.001
    f = VelocityDifferentiator(1, cutoff_hz=fc)
    f.update(0.0, [0.0])
    # velocity ramps with slope 1 from t = 0: the raw derivative steps from 0 to 1
    estimates = [f.update(k * dt, [k * dt])[0] for k in range(1, 200)]
    tau = 1 / (2 * math.pi * fc)
    k_tau = int(round(tau / dt))
    assert estimates[k_tau - 1] == pytest.approx(1 - math.exp(-1), abs=0.02)


def test_a_repeated_or_older_stamp_is_skipped():
    f = VelocityDifferentiator(1, cutoff_hz=20.0)
    f.update(0.0, [0.0])
    estimate = f.update(0.01, [1.0])[0]
    assert estimate > 0
    assert f.update(0.01, [7.0]) == [estimate]  # same stamp, e.g. a second publisher
    assert f.update(0.005, [-3.0]) == [estimate]  # older
    assert f.update(0.02, [2.0])[0] > estimate  # continues from the sample at 0.01


def test_a_gap_restarts_from_zero():
    f = VelocityDifferentiator(1, cutoff_hz=20.0, max_gap=0.1)
    f.update(0.0, [0.0])
    assert f.update(0.01, [1.0])[0] > 0
    assert f.update(1.0, [5.0]) == [0.0]  # a gap of 0.99 s
    assert f.update(1.01, [5.0]) == [0.0]  # and on from there


def test_cutoff_must_be_positive():
    with pytest.raises(ValueError, match="cutoff"):
        VelocityDifferentiator(2, cutoff_hz=0.0)
