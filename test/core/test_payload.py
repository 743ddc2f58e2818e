"""Payload analysis: the report's permissible torques (section 10), worst static poses and
exact largest payloads, checked against the dynamics core and brute-force sampling."""

import math
from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics.core import ModelError, RigidBody, RobotModel, gravity, gravity_batch, irb140, rnea
from irb140_dynamics.core.payload import (
    RTOL,
    check_payload,
    derive_torque_limits,
    max_payload_at,
    payload_family,
    workspace_load,
)
from irb140_dynamics.core.payload.workspace import harmonic_argmax, quasi_random

STRETCHED = [0.0, -math.pi / 2, math.pi / 2, 0.0, 0.0, 0.0]
SIX_KG = [0.0, 290.765, 105.348, 0.0, 6.25594, 0.0]  # report eq. 57
PERMISSIBLE = {1: 290.765, 2: 105.348, 4: 6.25594}  # joints 2, 3, 5 (indices)
# joint 4 with the wrist bent 90 deg: the same 6 kg and link 6 at 0.065 and 0.0325 m
JOINT_4 = 9.81 * (6.0 * 0.065 + irb140().joints[5].link.mass * 0.0325)

OFFSET_PAYLOADS = [
    RigidBody(6.0),
    RigidBody(3.0, (0.05, 0.0, 0.1)),
    RigidBody(2.0, (0.0, -0.08, 0.2), (0.01, 0.02, 0.015, 0.0, 0.0, 0.0)),
    RigidBody(4.0, (0.1, 0.1, -0.03), (0.03, 0.02, 0.02, 0.001, 0.0, 0.0)),
]
STATES = [
    (STRETCHED, [0.0] * 6),
    ([0.3, -1.0, 1.2, 0.5, 0.2, 0.1], [0.5, -0.4, 0.8, 1.0, -1.5, 2.0]),
    ([-2.0, 0.4, 2.5, -1.0, 1.3, 3.0], [0.0, 0.2, -0.3, 0.0, 0.5, 0.0]),
]


@pytest.fixture(scope="module")
def dense_poses(model):
    """Many poses over the joint ranges: a grid of multiples of 15 deg (45 and 90 deg for
    joints 4, 1 and 6) and random poses."""
    lower, upper = np.degrees([j.position_limits for j in model.joints]).T
    steps = (90, 15, 15, 45, 15, 90)
    axes = [np.radians(np.arange(math.ceil(lo / s) * s, up + 1e-9, s)) for lo, up, s in zip(lower, upper, steps)]
    axes[5] = axes[5][np.abs(axes[5]) <= math.pi]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 6)
    lower, upper = np.radians(lower), np.radians(upper)
    scattered = lower + np.random.default_rng(7).random((100_000, 6)) * (upper - lower)
    return np.vstack([grid, scattered])


def loaded(model, payload, mass):
    return model.with_payload(RigidBody(mass, payload.com, payload.inertia))


# -- the exact 1-D maximum the sweep rests on ---------------------------------------------------


def test_static_torque_is_harmonic_in_each_angle(model):
    heavy = model.with_payload(RigidBody(4.0, (0.1, 0.1, -0.03)))
    q = np.array(STATES[2][0])
    for k in range(6):
        Q = np.tile(q, (7, 1))
        Q[:, k] += np.linspace(0, 5, 7)
        g = gravity_batch(heavy, Q)
        basis = np.column_stack([np.ones(7), np.cos(Q[:, k]), np.sin(Q[:, k])])
        fit = np.linalg.lstsq(basis[:3], g[:3], rcond=None)[0]
        np.testing.assert_allclose(basis @ fit, g, atol=1e-11)


def test_harmonic_argmax():
    # 2 + cos(x - 1): the peak at 1 if inside, else the better end
    A, B, C = 2.0, math.cos(1.0), math.sin(1.0)
    assert harmonic_argmax(A, B, C, -3.0, 3.0)[0] == pytest.approx(1.0)
    assert harmonic_argmax(A, B, C, 2.0, 10.0)[0] == pytest.approx(1.0 + 2 * math.pi)
    x, top = harmonic_argmax(A, B, C, -2.0, 0.5)
    assert x == 0.5 and top == pytest.approx(2 + math.cos(0.5))
    x, _ = harmonic_argmax(A, B, C, 3.0, 4.0)  # 3 is 2 from the peak, 4 is 2.28 from the next
    assert x == 3.0


def test_quasi_random_fills_the_cube():
    U = quasi_random(4096, 6)
    assert U.min() >= 0 and U.max() < 1
    assert np.all(np.abs(U.mean(axis=0) - 0.5) < 1e-3)


# -- the report's permissible torques ---------------------------------------------------------------


def test_six_kg_stretched_is_the_report(model, limits):
    check = check_payload(model, RigidBody(6.0), limits, q=STRETCHED)
    np.testing.assert_allclose(check.torque, SIX_KG, atol=1e-3)
    assert check.ok
    assert np.all(check.use[[1, 2, 4]] >= 99.99)
    assert np.all(check.use <= 100 * (1 + RTOL))
    assert math.isinf(check.limit[0]) and math.isinf(check.limit[5])
    assert check.limits.source[0] == check.limits.source[5] == "none"
    assert check.max_payload_here.mass == pytest.approx(6.0, rel=1e-12)
    assert check.max_payload_here.joint == 1
    assert check.workspace.max_payload.mass == pytest.approx(6.0, rel=1e-12)


def test_heavier_payload_fails_at_joint_2(model, limits):
    check = check_payload(model, RigidBody(7.0), limits, q=STRETCHED)
    assert not check.ok
    assert not check.within[1] and check.beyond[1] and check.use[1] > 100
    assert check.max_payload_here.mass == pytest.approx(6.0, rel=1e-12)
    assert check.max_payload_here.joint == 1
    assert check.workspace.max_payload.joint == 1
    report = check.report()
    verdict = report.splitlines()[0]
    assert verdict.startswith("OVER-LIMIT: 7.000 kg does not fit: ") and "joint_2" in verdict
    assert check.verdict == "OVER-LIMIT" and "joint_2" in check.over
    print(report)


def test_derived_limits_are_the_permissible_torques(model, limits):
    assert limits.source == ("none", "derived", "derived", "derived", "derived", "none")
    # the report prints them rounded
    derived = [limits.values[j] for j in PERMISSIBLE]
    np.testing.assert_allclose(derived, list(PERMISSIBLE.values()), atol=5e-4)
    # exact against the core in the stretched pose, the worst for joints 2, 3 and 5
    rated_stretched = gravity(model.with_payload(RigidBody(6.0)), STRETCHED)
    np.testing.assert_allclose(derived, rated_stretched[list(PERMISSIBLE)], rtol=1e-9)
    assert limits.values[3] == pytest.approx(JOINT_4, rel=1e-9)
    np.testing.assert_allclose(np.degrees(limits.rated_pose[1]), [0, -90, 90, 0, 0, 0], atol=1e-6)
    np.testing.assert_allclose(np.degrees(limits.rated_pose[3][3:5]) % 180, [90, 90], atol=1e-6)


def test_no_pose_exceeds_the_derived_limits(model, limits, dense_poses):
    g = np.abs(gravity_batch(model.with_payload(RigidBody(6.0)), dense_poses))
    L = np.array(limits.values)
    assert np.all(g <= L * (1 + 1e-12))
    derived = np.isfinite(L)
    assert np.all(g.max(axis=0)[derived] >= 0.999 * L[derived])  # and the grid comes close
    # the worst poses found are real poses with exactly those torques
    at_worst = gravity_batch(model.with_payload(RigidBody(6.0)), limits.rated_pose)
    np.testing.assert_allclose(np.abs(np.diag(at_worst))[derived], L[derived], rtol=1e-12)


def test_given_limits_override(model):
    params = model.to_params()
    params["joint_1.torque_limit"] = 50.0
    params["joint_2.torque_limit"] = 400.0
    given = derive_torque_limits(RobotModel.from_params(params))
    assert given.source[:3] == ("given", "given", "derived")
    assert given.values[:2] == (50.0, 400.0)
    assert given.values[2] == pytest.approx(PERMISSIBLE[2], abs=5e-4)
    # 7 kg now passes joint 2 and joint 3 bounds the payload
    check = check_payload(model, RigidBody(7.0), given, q=STRETCHED)
    assert check.within[1] and not check.within[2]
    assert check.max_payload_here.joint == 2


# -- exact largest payloads -------------------------------------------------------------------------


@pytest.mark.parametrize("payload", OFFSET_PAYLOADS)
@pytest.mark.parametrize("q, qd", STATES)
def test_max_payload_puts_a_joint_at_its_limit(model, limits, payload, q, qd):
    best = max_payload_at(model, payload, limits, q, qd)
    L = np.array(limits.values)
    tau = rnea(loaded(model, payload, best.mass), q, qd, np.zeros(6))
    assert abs(tau[best.joint]) == pytest.approx(L[best.joint], rel=1e-9)
    assert np.all(np.abs(tau) <= L * (1 + 1e-9))
    heavier = rnea(loaded(model, payload, best.mass * (1 + 1e-6)), q, qd, np.zeros(6))
    assert abs(heavier[best.joint]) > L[best.joint]


@pytest.mark.parametrize("payload", OFFSET_PAYLOADS)
def test_workspace_max_payload_holds_everywhere(model, limits, payload, dense_poses, quick_proofs):
    """The mass is proven to hold in every pose; mass + gap puts a joint at its limit in a
    real pose (the gap: what the proof's budget left open; these off-axis payloads leave
    curves of worst wrist poses, which a small budget leaves open a little)."""
    load = workspace_load(model, payload, limits)
    best = load.max_payload
    L = np.array(limits.values)
    assert 0.0 <= best.gap <= 1e-2 * best.mass
    at_limit = gravity(loaded(model, payload, best.mass + best.gap), best.q)
    assert abs(at_limit[best.joint]) == pytest.approx(L[best.joint], rel=1e-9)
    g = gravity_batch(loaded(model, payload, best.mass), dense_poses)
    assert np.all(np.abs(g) <= L * (1 + 1e-9))
    # the worst static torques of the payload itself: real, and never exceeded
    at_worst = gravity_batch(model.with_payload(payload), load.pose)
    np.testing.assert_allclose(np.diag(at_worst), load.torque, rtol=1e-12, atol=1e-9)
    g = np.abs(gravity_batch(model.with_payload(payload), dense_poses))
    assert np.all(g <= load.bound + 1e-12 * load.bound.max())  # (float rounding of the kernels)
    assert np.all(load.gap >= 0) and np.all(load.gap <= 5e-2 * np.maximum(np.abs(load.torque), 1.0))


def test_no_payload_fits_when_the_arm_alone_is_over(model):
    params = model.to_params()
    params["joint_2.torque_limit"] = 100.0  # the arm alone needs 243 N m stretched
    tight = RobotModel.from_params(params)
    check = check_payload(tight, RigidBody(1.0), q=STRETCHED)
    assert math.isnan(check.max_payload_here.mass) and check.max_payload_here.joint == 1
    assert math.isnan(check.workspace.max_payload.mass)
    assert "none (joint_2 over its limit)" in check.report()


def test_unbounded_when_no_limit_is_loaded(model, quick_proofs):
    only_joint_1 = [50.0] + [math.inf] * 5  # a payload on the flange cannot turn joint 1 statically
    assert max_payload_at(model, RigidBody(3.0, (0.1, 0, 0)), only_joint_1, STRETCHED).mass == math.inf
    assert workspace_load(model, RigidBody(3.0, (0.1, 0, 0)), only_joint_1).max_payload.mass == math.inf


def test_payload_family_takes_the_payload_as_validated(model, limits, monkeypatch):
    """The payload of a model is valid: no re-validation per call; a new shape is checked
    once, by the models of its family."""
    family = payload_family(model, RigidBody(2.0, (0.0, 0.0, 0.1)))
    carrying = model.with_payload(RigidBody(1.0))
    check_payload(model, RigidBody(2.0, (0.0, 0.0, 0.1)), limits, q=STRETCHED)  # its shape checked once

    def validated(*args):
        raise AssertionError("validated again")

    monkeypatch.setattr(RigidBody, "validated", validated)
    assert payload_family(model, RigidBody(5.0, (0.0, 0.0, 0.1))) is family  # any mass
    assert payload_family(carrying, RigidBody(2.0, [0.0, 0.0, 0.1])) is family  # any payload the arm carries
    check_payload(model, RigidBody(5.0, (0.0, 0.0, 0.1)), limits, q=STRETCHED)
    monkeypatch.undo()
    with pytest.raises(ModelError, match="^payload.com: must be finite"):
        payload_family(model, RigidBody(1.0, (math.nan, 0.0, 0.0)))
    with pytest.raises(ModelError, match="^payload.inertia: "):
        payload_family(model, RigidBody(1.0, (0.0, 0.0, 0.0), (1.0, 1.0, 3.0, 0.0, 0.0, 0.0)))


def test_the_payload_sits_on_the_model_s_flange(model, limits):
    """A flange 0.1 m out along z: a payload at its origin loads the arm as one 0.1 m out
    on the last link (the payload's models keep the flange)."""
    from irb140_dynamics.core.model.joints import Placement

    flanged = replace(model, flange=Placement(xyz=(0.0, 0.0, 0.1)))
    here = max_payload_at(flanged, RigidBody(2.0), limits, STATES[1][0], STATES[1][1])
    there = max_payload_at(model, RigidBody(2.0, (0.0, 0.0, 0.1)), limits, STATES[1][0], STATES[1][1])
    assert here.mass == pytest.approx(there.mass, rel=1e-12) and here.joint == there.joint
    load = workspace_load(flanged, RigidBody(2.0), limits)
    np.testing.assert_allclose(
        load.torque, workspace_load(model, RigidBody(2.0, (0.0, 0.0, 0.1)), limits).torque, rtol=1e-9, atol=1e-9
    )
