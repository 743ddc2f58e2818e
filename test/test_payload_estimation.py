"""Payload estimation from efforts at rest: accurate from poses that differ in the wrist,
refused with advice from too few or too similar poses."""

from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics.core import Friction, RigidBody, gravity, irb140, rnea
from irb140_dynamics.core.payload_estimation import (
    EstimationError,
    RestDetector,
    RestSample,
    estimate_payload,
    payload_columns,
)

from .support import random_urdf_model

PAYLOAD = RigidBody(3.0, (0.05, 0.02, 0.10))
WRIST_POSES = [
    [0.3, -0.4, 0.5, 0.0, 0.3, 0.0],
    [0.3, -0.4, 0.5, 1.2, -0.8, 0.5],
    [0.3, -0.4, 0.5, -0.7, 1.2, 1.7],
    [0.3, -0.4, 0.5, 0.4, 0.9, -1.5],
]


def arm():
    model = irb140()
    return replace(model, joints=tuple(replace(j, friction=Friction(1.0, 4.0)) for j in model.joints))


def rest_samples(model, true, poses, rng, per_pose=300):
    """Joint states at rest in each pose, efforts from the model with noise 1 % of each
    joint's peak, through the rest detector as a node would feed it."""
    peak = np.max(np.abs([gravity(true, q) for q in poses]), axis=0)
    detector = RestDetector(rest_velocity=0.01, rest_time=0.2)
    t = 0.0
    for q in poses:
        for _ in range(per_pose):
            t += 0.001
            effort = rnea(true, q, np.zeros(6), np.zeros(6)) + rng.normal(0.0, 0.01 * peak)
            detector.update(t, q, np.full(6, 1e-4), effort)
        detector.update(t + 0.001, q, np.full(6, 0.5), effort)  # moves on
    return detector.samples


@pytest.mark.parametrize("make", [lambda: irb140(), lambda: random_urdf_model(np.random.default_rng(5), 6)])
def test_columns_are_the_payload_torques(make):
    model = make()
    rng = np.random.default_rng(1)
    for _ in range(10):
        q = rng.uniform(-3, 3, model.n)
        payload = RigidBody(rng.uniform(0.5, 5), tuple(rng.uniform(-0.2, 0.2, 3)))
        phi = np.array([payload.mass, *(payload.mass * np.array(payload.com))])
        expected = gravity(model.with_payload(payload), q) - gravity(model.with_payload(RigidBody()), q)
        np.testing.assert_allclose(payload_columns(model, q) @ phi, expected, atol=1e-10)


def test_four_wrist_poses_give_mass_and_com():
    model = arm()
    samples = rest_samples(model, model.with_payload(PAYLOAD), WRIST_POSES, np.random.default_rng(2))
    assert len(samples) == 4
    estimate = estimate_payload(model, samples)
    assert estimate.mass == pytest.approx(3.0, rel=0.02)
    assert np.linalg.norm(np.subtract(estimate.com, PAYLOAD.com)) < 0.005
    assert estimate.poses == 4 and estimate.condition < 100
    assert abs(estimate.mass - 3.0) < 4 * estimate.mass_std + 1e-3


def test_two_poses_are_refused():
    model = arm()
    samples = rest_samples(model, model.with_payload(PAYLOAD), WRIST_POSES[:2], np.random.default_rng(3))
    with pytest.raises(EstimationError, match="at least 3"):
        estimate_payload(model, samples)


def test_poses_differing_only_in_joint_1_are_refused_with_advice():
    model = arm()
    poses = [[a, -0.4, 0.5, 0.0, 0.3, 0.0] for a in (0.0, 0.8, 1.6, 2.4)]
    samples = rest_samples(model, model.with_payload(PAYLOAD), poses, np.random.default_rng(4))
    with pytest.raises(EstimationError, match="too similar.*joint"):
        estimate_payload(model, samples)


def test_implausible_estimates_are_refused():
    model = arm()
    q = np.array(WRIST_POSES)
    lifting = [RestSample(p, gravity(model, p) - 0.5 * (gravity(model.with_payload(PAYLOAD), p) - gravity(model, p)), 1) for p in q]
    with pytest.raises(EstimationError, match="mass"):
        estimate_payload(model, lifting)
    far = model.with_payload(RigidBody(1.0, (0.0, 0.0, 0.9)))
    with pytest.raises(EstimationError, match="CoM"):
        estimate_payload(model, [RestSample(p, gravity(far, p), 1) for p in q])


def test_rest_detector_needs_rest_time_and_merges_the_same_pose():
    detector = RestDetector(rest_velocity=0.01, rest_time=0.5)
    q, effort = np.zeros(6), np.ones(6)
    for k in range(100):  # 0.1 s: too short
        detector.update(k * 0.001, q, np.zeros(6), effort)
    assert not detector.update(0.2, q, np.ones(6), effort) and detector.samples == []
    for start in (1.0, 3.0):  # the same pose twice: one sample
        for k in range(600):
            detector.update(start + k * 0.001, q, np.zeros(6), effort)
        detector.update(start + 0.7, q, np.ones(6), effort)
    assert len(detector.samples) == 1 and detector.samples[0].count == 600
    for k in range(600):  # an effort missing ends the rest too
        detector.update(5 + k * 0.001, q + 0.1, np.zeros(6), effort)
    assert detector.update(6.0, q + 0.1, np.zeros(6), None) and len(detector.samples) == 2
    detector.clear()
    assert detector.samples == []
