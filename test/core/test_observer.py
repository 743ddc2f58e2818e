"""The generalized momentum observer: exact terms, no residual without contact, the
external torque as a first-order lag, and resets on bad time steps."""

import math
from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics import native
from irb140_dynamics.core import Friction, RigidBody, coriolis_matrix, gravity, irb140, mass_matrix, rnea
from irb140_dynamics.core.codegen.kernels import kernels_of, prepare
from irb140_dynamics.core.monitoring.observer import MomentumObserver, monitor_terms

from ..support.common import random_urdf_model

RATE = 1000.0  # Hz
GAIN = 100.0  # 1/s


def arm_with_friction():
    model = irb140()
    return replace(model, joints=tuple(replace(j, friction=Friction(2.0, 3.0), armature=0.1) for j in model.joints))


def fast_motion(t):
    """q, qd, qdd of a fast smooth motion of every joint (up to ~2.5 rad/s, 15 rad/s^2)."""
    w = np.array([2.0, 2.5, 3.0, 3.5, 4.0, 4.5])
    A = np.array([0.8, 0.5, 0.6, 0.7, 0.6, 0.5])
    return A * np.sin(w * t), A * w * np.cos(w * t), -A * w**2 * np.sin(w * t)


@pytest.mark.parametrize(
    "make", [arm_with_friction, lambda: random_urdf_model(np.random.default_rng(3), 6, friction=True)]
)
def test_momentum_terms_are_exact(make):
    model = make()
    rng = np.random.default_rng(0)
    for _ in range(20):
        q, qd = rng.normal(size=(2, model.n))
        p, ct_qd = np.split(np.array(kernels_of(model).momentum.scalar(list(q), list(qd))), 2)
        np.testing.assert_allclose(p, mass_matrix(model, q) @ qd, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ct_qd, coriolis_matrix(model, q, qd).T @ qd, rtol=1e-11, atol=1e-11)


@pytest.mark.parametrize(
    "make", [arm_with_friction, lambda: random_urdf_model(np.random.default_rng(4), 6, friction=True)]
)
def test_monitor_terms_are_the_separate_algorithms_to_the_last_bit(make):
    """One pass (the node's, for joint states with efforts) gives exactly what rnea, gravity
    and the observer's own terms give: the same operations, shared."""
    model = make()
    observer = MomentumObserver(model, GAIN)
    rng = np.random.default_rng(1)
    for _ in range(50):
        q, qd, qdd = (rng.uniform(-3.0, 3.0, model.n).tolist() for _ in range(3))
        tau, g, p, beta = monitor_terms(model, q, qd, qdd)
        assert tau == rnea(model, q, qd, qdd).tolist() and g == gravity(model, q).tolist()
        assert (p, beta) == tuple(observer._momentum_terms(q, qd))
    with pytest.raises(ValueError, match="rnea: the result is not finite"), np.errstate(all="ignore"):
        monitor_terms(model, [0.0] * model.n, [1e200] * model.n, [0.0] * model.n)


@pytest.mark.skipif(not native.enabled(), reason="no C compiler (or IRB140_NATIVE=0)")
def test_monitor_terms_of_arrays_run_native_to_the_same_bits(monkeypatch):
    """Float64 arrays go to the C kernel (the node's joint states), lists to the Python form:
    the same numbers, the refusal of a non-finite result the same."""
    model = arm_with_friction()
    assert prepare(model, names=("monitor",)).native
    kernel = kernels_of(model).monitor
    python_calls = []
    monkeypatch.setattr(kernel, "used", lambda: python_calls.append(1))
    rng = np.random.default_rng(2)
    for _ in range(50):
        q, qd, qdd = (rng.uniform(-3.0, 3.0, model.n) for _ in range(3))
        before = len(python_calls)
        from_arrays = monitor_terms(model, q, qd, qdd)
        assert len(python_calls) == before  # no call of the Python form
        assert from_arrays == monitor_terms(model, q.tolist(), qd.tolist(), qdd.tolist())
    assert len(python_calls) == 50
    with pytest.raises(ValueError, match="rnea: the result is not finite"), np.errstate(all="ignore"):
        monitor_terms(model, np.zeros(model.n), np.full(model.n, 1e200), np.zeros(model.n))


def run(model, duration, external=lambda t: np.zeros(6), observer=None):
    """Feed the observer the efforts that drive fast_motion against ``external``; residuals."""
    observer = observer or MomentumObserver(model, GAIN)
    times = np.arange(int(duration * RATE)) / RATE
    residuals = []
    for t in times:
        q, qd, qdd = fast_motion(t)
        tau = rnea(model, q, qd, qdd) - external(t)  # the arm moves so: the motors do the rest
        residuals.append(observer.update(t, q, qd, tau))
    return times, np.array(residuals)


def test_no_contact_no_residual():
    model = arm_with_friction()
    times, r = run(model, 2.0)
    peak = np.max(np.abs([rnea(model, *fast_motion(t)) for t in times]), axis=0)
    assert np.all(np.abs(r) <= 0.01 * peak.max()), np.abs(r).max(axis=0)


def test_step_external_torque_is_a_first_order_lag():
    model = arm_with_friction()
    step_at = 0.3
    ext = np.array([0.0, 20.0, 0.0, 0.0, 0.0, 0.0])
    times, r = run(model, step_at + 5 / GAIN + 0.01, lambda t: ext if t >= step_at else np.zeros(6))
    after = times >= step_at + 5 / GAIN
    assert abs(r[after][0, 1] - 20.0) <= 0.05 * 20.0
    np.testing.assert_allclose(r[after][0, [0, 2, 3, 4, 5]], 0.0, atol=0.2)
    # it crosses a 10 N m threshold within 10 ms of the step
    crossed = times[np.argmax(r[:, 1] > 10.0)]
    assert step_at < crossed <= step_at + 0.010 + 1e-9


@pytest.mark.parametrize("gain", [1500.0, 2500.0, 1e4])  # K dt 1.5 to 10 at 1 kHz: the explicit step rang or diverged
def test_a_gain_beyond_the_sampling_rate_neither_rings_nor_diverges(gain):
    model = arm_with_friction()
    ext = np.array([0.0, 20.0, 0.0, 0.0, 0.0, 0.0])
    observer = MomentumObserver(model, gain)
    times, r = run(model, 0.2, lambda t: ext if t >= 0.1 else np.zeros(6), observer)
    before, after = r[times < 0.1], r[times >= 0.1]
    assert np.abs(before).max() < 0.2
    assert after[:, 1].max() <= 20.0 * 1.01  # no overshoot
    assert np.all(np.diff(after[:, 1]) > -0.05)  # a rise, no ringing
    assert abs(after[-1, 1] - 20.0) < 0.2


def test_unmodelled_payload_shows_as_its_gravity_torque():
    model = irb140()
    true = model.with_payload(RigidBody(2.0, (0.0, 0.0, 0.05)))
    observer = MomentumObserver(model, GAIN)
    q = np.array([0.2, -0.5, 0.7, 0.3, 0.9, 0.0])
    for k in range(200):  # at rest: the motors hold arm and payload
        r = observer.update(k / RATE, q, np.zeros(6), gravity(true, q))
    np.testing.assert_allclose(r, -(gravity(true, q) - gravity(model, q)), atol=1e-6)


def test_gaps_and_backward_stamps_reset_the_observer():
    model = irb140()
    observer = MomentumObserver(model, GAIN, max_gap=0.1)
    q = np.zeros(6)
    g = gravity(model, q)
    for k in range(50):
        observer.update(k / RATE, q, np.zeros(6), g - 5.0)
    assert np.all(np.abs(observer.r) > 1.0) and observer.restarted is None
    for t, kind in ((0.049, "repeated_stamp"), (0.049, "older_stamp"), (1.0, "gap")):
        assert np.all(observer.update(t, q, np.zeros(6), g - 5.0) == 0.0)
        assert observer.restarted == kind
        observer.update(t + 0.001, q, np.zeros(6), g - 5.0)
        assert observer.restarted is None
        observer._r = [1.0] * 6  # pretend it had run on
    observer.reset()
    observer.update(2.0, q, np.zeros(6), g)
    assert observer.restarted is None  # the first sample after a reset: a start, no restart


def test_bad_values_are_refused():
    observer = MomentumObserver(irb140(), GAIN)
    with pytest.raises(ValueError, match="tau"):
        observer.update(0.0, np.zeros(6), np.zeros(6), [math.nan] * 6)
    with pytest.raises(ValueError, match="gain"):
        MomentumObserver(irb140(), 0.0)
