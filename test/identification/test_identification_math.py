"""Filtering and differentiation, normal equations, least squares, the consistent fit, YAML files."""

from dataclasses import replace

import numpy as np
import pytest
import yaml
from scipy.signal import freqz, savgol_filter

from irb140_dynamics.core import RigidBody, RobotModel, irb140, rnea_batch
from irb140_dynamics.core.io.params_file import parameter_file_text, read_parameter_file
from irb140_dynamics.core.io.trajectory_file import joint_trajectory_text
from irb140_dynamics.core.io.yaml_numbers import yaml_float
from irb140_dynamics.core.regressor import inertial_parameters, parameters_body, regressor_batch
from irb140_dynamics.identification.base import find_base_parameters, random_states
from irb140_dynamics.identification.consistent import (
    consistent_parameters,
    is_consistent,
    log_cholesky,
    log_cholesky_of,
    parameters_and_jacobian,
    parameters_of,
    pseudo_inertia,
)
from irb140_dynamics.identification.least_squares import NormalEquations, weighted_least_squares
from irb140_dynamics.identification.recording import RawChunk
from irb140_dynamics.identification.signals import MAX_WINDOW, POLYORDER, Differentiator, FilterDesign

from ..support.synthetic_arm import true_arm

N_JOINTS = 2


def chunks_of(time, position, effort, sizes):
    """RawChunks of the samples, cut at the given sizes (repeated)."""
    start, k = 0, 0
    while start < len(time):
        end = min(start + sizes[k % len(sizes)], len(time))
        nan = np.full((end - start, position.shape[1]), np.nan)
        yield RawChunk(start, time[start:end], position[start:end], nan, effort[start:end])
        start, k = end, k + 1


def run(design, chunks):
    differentiator = Differentiator(design, N_JOINTS, has_velocity=False)
    parts = [p for p in (differentiator.push(c) for c in chunks) if p is not None]
    differentiator.finish()
    return parts, differentiator


def test_design_follows_the_cutoff():
    design = FilterDesign.of(1000.0, 10.0)
    w, h = freqz(design.coefficients(0), worN=[2 * np.pi * f / 1000.0 for f in (0.5, 10.0, 50.0)])
    gain = np.abs(h)
    assert abs(gain[0] - 1.0) < 1e-4  # the excitation's band passes untouched
    assert 0.6 < gain[1] < 0.8  # -3 dB near the cut-off
    assert gain[2] < 0.15
    assert design.window % 2 == 1 and design.stride == 25


@pytest.mark.parametrize("rate, cutoff", [(2.5e8, 10.0), (250.0, 1e-6)])
def test_a_window_too_long_to_filter_is_refused_before_any_work(rate, cutoff):
    """Time stamps in the wrong unit (microseconds read as seconds) or a tiny cut-off would
    ask for a window of millions of samples: memory and time beyond any recording."""
    with pytest.raises(ValueError, match=r"filter window of [0-9,]+ samples, more than [0-9,]+: raise --cutoff"):
        FilterDesign.of(rate, cutoff)
    assert FilterDesign.of(10_000.0, 1.0).window <= MAX_WINDOW  # a fast logger, a slow motion: still filtered


def test_streaming_filter_is_the_whole_segment_filter_whatever_the_chunks():
    rate, design = 200.0, FilterDesign.of(200.0, 8.0)
    t = np.arange(1000) / rate
    q = np.column_stack([np.sin(1.3 * t), 0.2 * t**3])
    tau = np.column_stack([np.cos(2.0 * t), t])
    reference, _ = run(design, chunks_of(t, q, tau, [10**6]))
    for sizes in ([7], [50, 3, 200], [999, 1]):
        parts, _ = run(design, chunks_of(t, q, tau, sizes))
        for field in ("index", "q", "qd", "qdd", "tau"):
            np.testing.assert_allclose(
                np.concatenate([getattr(p, field) for p in parts]),
                np.concatenate([getattr(p, field) for p in reference]),
                rtol=1e-12,
                atol=1e-12,
            )
    points = reference[0]
    expected = savgol_filter(q, design.window, POLYORDER, deriv=2, delta=1 / rate, axis=0)[points.index]
    np.testing.assert_allclose(points.qdd, expected, rtol=1e-9, atol=1e-9)
    assert np.all(np.diff(points.index) == design.stride) and points.index[0] == design.half


def test_polynomials_up_to_the_filter_degree_differentiate_exactly():
    rate = 100.0
    design = FilterDesign.of(rate, 5.0)
    t = 3.0 + np.arange(400) / rate
    q = np.column_stack([2.0 - t + 0.5 * t**2 - 0.1 * t**3 + 0.01 * t**4, np.full_like(t, 0.7)])
    parts, _ = run(design, chunks_of(t, q, q, [64]))
    points = replace(parts[0], **{f: np.concatenate([getattr(p, f) for p in parts]) for f in ("time", "qd", "qdd")})
    s = points.time
    np.testing.assert_allclose(points.qd[:, 0], -1 + s - 0.3 * s**2 + 0.04 * s**3, rtol=1e-7, atol=1e-7)
    np.testing.assert_allclose(points.qdd[:, 0], 1 - 0.6 * s + 0.12 * s**2, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(points.qd[:, 1], 0.0, atol=1e-9)


def test_gaps_and_missing_values_split_segments_and_are_counted():
    rate = 100.0
    design = FilterDesign.of(rate, 10.0)
    t = np.arange(600) / rate
    t[300:] += 0.5  # a gap of half a second
    q = np.column_stack([np.sin(t), np.cos(t)])
    tau = q.copy()
    tau[100] = np.nan  # a sample without effort
    t[450] = t[449]  # a repeated stamp: irregular steps before and after it
    parts, differentiator = run(design, chunks_of(t, q, tau, [128]))
    index = np.concatenate([p.index for p in parts])
    assert differentiator.invalid_samples == 1
    # segments [0, 100), [101, 300), [300, 450), [450], [451, 600): both ends of each are edges
    assert differentiator.edge_samples == 4 * 2 * design.half + 1
    for start, end in ((0, 100), (101, 300), (300, 450), (451, 600)):
        inside = index[(index >= start) & (index < end)]
        assert inside.min() >= start + design.half and inside.max() < end - design.half


def test_noise_correlation_of_white_noise_after_filtering():
    design = FilterDesign.of(500.0, 10.0)
    h = design.coefficients(0)
    noise = np.random.default_rng(0).normal(size=400_000)
    filtered = np.convolve(noise, h, mode="valid")[:: design.stride]
    blocks = filtered[: len(filtered) // 50 * 50].reshape(-1, 50).mean(axis=1)  # means of 50 fit points
    inflation = blocks.var() * 50 / filtered.var()  # their variance / the white-noise formula's
    assert inflation == pytest.approx(design.noise_correlation(), rel=0.15)


def test_normal_equations_give_exact_residuals():
    rng = np.random.default_rng(1)
    model = irb140()
    Y = regressor_batch(model, *random_states(model, 40, rng))
    tau, use = rng.normal(size=(40, 6)) * 10, rng.random((40, 6)) > 0.2
    equations = NormalEquations(6, 78)
    equations.add(Y[:25], tau[:25], use[:25])
    equations.add(Y[25:], tau[25:], use[25:])
    pi = rng.normal(size=78)
    residual = np.where(use, Y @ pi - tau, 0.0)
    np.testing.assert_allclose(equations.rss(pi), (residual**2).sum(axis=0), rtol=1e-9)
    assert list(equations.rows) == list(use.sum(axis=0))
    np.testing.assert_allclose(equations.peak, np.where(use, np.abs(tau), 0).max(axis=0))


@pytest.fixture(scope="module")
def base():
    return find_base_parameters(irb140())


def test_least_squares_recovers_exact_torques_and_refuses_too_little_motion(base):
    model, truth = irb140(), true_arm(1)
    states = random_states(model, 300, np.random.default_rng(2))
    equations = NormalEquations(6, 78)
    equations.add(regressor_batch(model, *states), rnea_batch(truth, *states), np.ones((300, 6), bool))
    estimate = weighted_least_squares(equations, base)
    np.testing.assert_allclose(estimate.beta, base.of(inertial_parameters(truth)), rtol=1e-7, atol=1e-7)
    still = NormalEquations(6, 78)
    Q = np.repeat(states[0][:1], 300, axis=0)
    still.add(regressor_batch(model, Q, 0 * Q, 0 * Q), rnea_batch(truth, Q, 0 * Q, 0 * Q), np.ones((300, 6), bool))
    with pytest.raises(ValueError, match="excite"):
        weighted_least_squares(still, base)


def test_log_cholesky_round_trip_and_jacobian():
    rng = np.random.default_rng(3)
    for _ in range(5):
        theta = rng.normal(size=10)
        J = log_cholesky(theta)
        assert np.linalg.eigvalsh(J)[0] > 0
        np.testing.assert_allclose(log_cholesky_of(J), theta, rtol=1e-9, atol=1e-9)
        pi10, jacobian = parameters_and_jacobian(theta)
        np.testing.assert_allclose(pseudo_inertia(pi10), J, rtol=1e-12, atol=1e-12)
        numeric = np.column_stack(
            [
                (parameters_of(log_cholesky(theta + 1e-6 * e)) - parameters_of(log_cholesky(theta - 1e-6 * e))) / 2e-6
                for e in np.eye(10)
            ]
        )
        np.testing.assert_allclose(jacobian, numeric, rtol=1e-6, atol=1e-6)
        parameters_body("link", pi10, irb140().joints[1].post)  # a physical body: no ModelError


@pytest.mark.slow
def test_consistent_fit_of_a_physical_estimate_reproduces_it(base):
    model, truth = irb140(), true_arm(2)
    states = random_states(model, 400, np.random.default_rng(4))
    equations = NormalEquations(6, 78)
    equations.add(
        regressor_batch(model, *states),
        rnea_batch(truth, *states) + np.random.default_rng(5).normal(size=(400, 6)) * 0.05,
        np.ones((400, 6), bool),
    )
    estimate = weighted_least_squares(equations, base)
    fit = consistent_parameters(model, base, estimate)
    assert fit.consistent and is_consistent(fit.pi, 6)
    assert np.abs(fit.deviation).max() < 2.0  # massless links 3 and 5 must stay physical in the noise
    assert isinstance(fit.model, RobotModel) and fit.model.payload == RigidBody()


@pytest.mark.slow
def test_consistent_fit_of_an_unphysical_estimate_stays_physical(base):
    """Torques asking for a negative mass on the last link get a physical arm, far from them."""
    model = irb140()
    pi = inertial_parameters(model)
    pi[50] = -3.0  # joint_6 mass: no body has it
    states = random_states(model, 300, np.random.default_rng(6))
    Y = regressor_batch(model, *states)
    equations = NormalEquations(6, 78)
    equations.add(Y, Y @ pi + np.random.default_rng(7).normal(size=(300, 6)) * 0.01, np.ones((300, 6), bool))
    fit = consistent_parameters(model, base, weighted_least_squares(equations, base), max_evaluations=60)
    assert fit.consistent and fit.pi[50] >= 0.0
    assert np.abs(fit.deviation).max() > 10.0


@pytest.mark.parametrize(
    "x, text",
    [
        (0.0, "0.0"),
        (2.0, "2.0"),
        (1e-05, "1.0e-05"),
        (-1.5e-07, "-1.5e-07"),
        (1e20, "1.0e+20"),
        (0.1, "0.1"),
        (3.141592653589793, "3.141592653589793"),
    ],
)
def test_yaml_floats_stay_floats(x, text):
    assert yaml_float(x) == text
    assert yaml.safe_load(text) == x and isinstance(yaml.safe_load(text), float)


def test_parameter_file_round_trips_a_model(tmp_path):
    model = replace(true_arm(3), smoothing_velocity=0.02)
    path = tmp_path / "model.yaml"
    path.write_text(parameter_file_text(model.to_params(), ["a comment", "another"]))
    text = path.read_text()
    assert text.startswith("# a comment\n# another\n/**:\n  ros__parameters:\n")
    assert RobotModel.from_params(read_parameter_file(path)) == model
    assert "    joint_3:\n      dh: [0.0, 1.5707963267948966, 0.0, 0.0]\n      link:\n        mass: 0.0\n" in text


def as_joint_trajectory(document: dict):
    """The message built from the YAML's fields, as ``ros2 topic pub`` does: the message
    classes check every field's type (a string where a double belongs would raise)."""
    from builtin_interfaces.msg import Duration
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

    points = [
        JointTrajectoryPoint(**{**p, "time_from_start": Duration(**p["time_from_start"])}) for p in document["points"]
    ]
    return JointTrajectory(joint_names=document["joint_names"], points=points)


@pytest.mark.ros  # builds trajectory_msgs messages
def test_trajectory_text_is_a_joint_trajectory_message():
    t = np.array([0.0, 0.05, 1.25, 2.0000000001])
    Q = np.arange(8.0).reshape(4, 2) * 0.1
    text = joint_trajectory_text(["a", "b"], t, Q, -Q, 1e-5 * Q, ["condition number: 12.5"])
    document = yaml.safe_load(text)
    assert set(document) == {"joint_names", "points"}
    message = as_joint_trajectory(document)
    assert list(message.joint_names) == ["a", "b"]
    assert [(p.time_from_start.sec, p.time_from_start.nanosec) for p in message.points] == [
        (0, 0),
        (0, 50_000_000),
        (1, 250_000_000),
        (2, 0),
    ]
    np.testing.assert_allclose([list(p.positions) for p in message.points], Q)
    np.testing.assert_allclose([list(p.accelerations) for p in message.points], 1e-5 * Q)
    assert all(isinstance(x, float) for p in document["points"] for x in p["velocities"])
    assert text.startswith("# condition number: 12.5\n")
