"""The worst static torques are proven, not only searched: Interval
numbers, the exact harmonic form of the static torques, the box bounds, and the branch
and bound against brute force; narrowed joint ranges with a small payload."""

import math
from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest

from irb140_dynamics.core import RigidBody, RobotModel, check_payload, derive_torque_limits, gravity, irb140
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.core.payload import workspace_load
from irb140_dynamics.core.payload.family import CERTIFY_RTOL, payload_family
from irb140_dynamics.core.payload.proof import certify
from irb140_dynamics.core.payload.proof.bounds import quadratic_max
from irb140_dynamics.core.payload.proof.harmonic import MAX_JOINTS, StaticForms
from irb140_dynamics.core.payload.workspace import JointRanges
from irb140_dynamics.core.scalars.interval import Interval

from ..support.common import random_model

# Narrowed ranges (q2..q6) and a 1.0646 kg payload, where a local search stops short of the
# worst joint-5 torque; FAR_POSE is beyond the search's maximum.
NARROWED_RANGES = {
    1: (-0.5791, -0.0241),
    2: (1.9343, 3.7139),
    3: (0.2400, 2.5213),
    4: (1.6978, 1.9185),
    5: (-5.9204, -4.2777),
}
NARROWED_PAYLOAD = RigidBody(1.0646, (0.02498, 0.00324, -0.00464))
FAR_POSE = [0.0, -0.56047, 1.93432, 0.23997, 1.69778, -5.92038]  # rounded: clipped into the ranges below


NO_PAYLOAD = RigidBody()


def with_ranges(model: RobotModel, ranges: dict, payload: RigidBody = NO_PAYLOAD) -> RobotModel:
    joints = tuple(replace(j, position_limits=ranges.get(i, j.position_limits)) for i, j in enumerate(model.joints))
    return RobotModel(joints, model.gravity, payload)


def dense_maxima(torque, ranges: JointRanges, rng, count=200_000) -> np.ndarray:
    """max +-tau_j over random poses in the ranges: (2n,), rows as in Extremes."""
    Q = ranges.lower + rng.random((count, ranges.lower.size)) * (ranges.upper - ranges.lower)
    tau = torque(Q)
    return np.concatenate([tau.max(axis=0), (-tau).max(axis=0)])


# -- the parts ---------------------------------------------------------------------------------------


def test_interval_arithmetic_encloses_the_exact_results():
    """+ - * of intervals contain the exact (rational) results of the same operations on any
    of their points, products with constants and 0 included."""
    rng = np.random.default_rng(1)
    for _ in range(200):
        a, b = np.sort(rng.normal(size=2) * 10.0 ** rng.integers(-3, 4)), np.sort(rng.normal(size=2))
        x, y, k = Interval(a[0], a[1]), Interval(b[0], b[1]), float(rng.choice([0.0, 1.0, -1.0, rng.normal()]))
        for u in (a[0], a[1], a.mean()):
            for v in (b[0], b[1], b.mean()):
                U, V, K = Fraction(float(u)), Fraction(float(v)), Fraction(k)
                for result, exact in (
                    (x + y, U + V),
                    (x - y, U - V),
                    (x * y, U * V),
                    (x * k, U * K),
                    (k - x, K - U),
                    (x + k, U + K),
                ):
                    lo, hi = (result.lo, result.hi) if isinstance(result, Interval) else (result, result)
                    assert Fraction(float(lo)) <= exact <= Fraction(float(hi))


def test_interval_arrays_round_as_their_elements_do_bit_for_bit():
    """On arrays (wide intervals, points, mixed; zeros, subnormals, huge and infinite
    values) + and * give each element's interval exactly as on that element alone."""
    rng = np.random.default_rng(2)
    special = np.array([0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, np.inf, -np.inf])
    values = np.concatenate([rng.normal(size=200) * 10.0 ** rng.integers(-300, 300, 200), special])
    width = np.abs(rng.normal(size=values.size)) * np.where(rng.random(values.size) < 0.5, 0.0, 1.0)
    point, wide = Interval(values), Interval(values - width, values + width)
    other = Interval(rng.permutation(values))
    with np.errstate(all="ignore"):
        for x, y in ((wide, other), (point, other), (other, wide), (wide, wide), (point, 3.0)):
            for result, element in ((x * y, lambda a, b: a * b), (x + y, lambda a, b: a + b)):
                for i in range(values.size):
                    a = Interval(float(x.lo[i]), float(x.hi[i]))
                    b = Interval(float(y.lo[i]), float(y.hi[i])) if isinstance(y, Interval) else y
                    alone = element(a, b)
                    for got, expected in ((result.lo[i], alone.lo), (result.hi[i], alone.hi)):
                        assert np.array_equal(got, expected, equal_nan=True), (i, got, expected)


@pytest.mark.parametrize("fn", ["cos", "sin"])
def test_interval_cos_and_sin_enclose_their_range(fn):
    rng = np.random.default_rng(2)
    lo = rng.uniform(-10, 10, 300)
    hi = lo + np.concatenate([rng.uniform(0, 0.5, 100), rng.uniform(0, 4, 100), rng.uniform(0, 8, 100)])
    box = getattr(Interval(lo, hi), fn)()
    x = lo[:, None] + np.linspace(0, 1, 2001) * (hi - lo)[:, None]
    values = getattr(np, fn)(x)
    assert np.all(box.lo <= values.min(axis=1)) and np.all(values.max(axis=1) <= box.hi)
    step = (hi - lo) / 2000
    assert np.all(box.hi - box.lo <= values.max(axis=1) - values.min(axis=1) + step**2 + 1e-12)  # and tight


@pytest.mark.parametrize("seed", [3, 4])
def test_harmonic_forms_are_the_static_torques(seed):
    rng = np.random.default_rng(seed)
    model = random_model(rng, 6)
    forms = StaticForms.of(model)
    theta = rng.uniform(-4, 4, (300, 6))
    q = theta - np.array(kernels_of(model).angles)
    tau = np.array([gravity(model, x) for x in q])
    np.testing.assert_allclose(forms.torque(theta), tau, rtol=0, atol=1e-12 * np.abs(tau).max())
    for j in range(6):  # Cauchy-Schwarz: |tau_j| <= |g| |omega_j|, omega_j not turned by joint j
        reach = forms.gravity_norm * np.linalg.norm(forms.omega[j](theta), axis=1)
        assert np.all(np.abs(tau[:, j]) <= reach * (1 + 1e-12) + 1e-12)


def test_irb140_sums_drop_and_merge_joints():
    """Joint 1 turns about gravity: no torque depends on it; joint 6 about the axis the
    rated payload and link 6 sit on; joints 2 and 3 are parallel: beyond them only their
    sum turns gravity, and a sum folded that way is the same function."""
    forms = StaticForms.of(irb140(payload=RigidBody(6.0)))
    assert forms.torque[0].reduced().dims == ()
    assert forms.torque[1].reduced().dims == (1, 2, 3, 4)
    merged = forms.torque[4].reduced(merge=True)
    assert merged.dims == (1, 3, 4) and merged.merges == ((1, 2, 1.0),)
    rng = np.random.default_rng(5)
    theta = rng.uniform(-3, 3, (50, 6))
    folded = theta.copy()
    folded[:, 1], folded[:, 2] = theta[:, 1] + theta[:, 2], 0.0
    basis = np.ones((50, 1))
    for d in merged.dims:
        phi = np.stack([np.ones(50), np.cos(folded[:, d]), np.sin(folded[:, d])], axis=1)
        basis = (basis[:, :, None] * phi[:, None, :]).reshape(50, -1)
    np.testing.assert_allclose(basis @ merged.coefficients, forms.torque(theta)[:, 4], atol=1e-12)
    assert merged.error < 1e-10  # the coefficients' own rounding, nothing lost by the merge


def test_quadratic_max_bounds_the_maximum_and_is_exact_for_a_concave_top_inside():
    rng = np.random.default_rng(6)
    B, d = 200, 3
    g, A = rng.normal(size=(B, d)), rng.normal(size=(B, d, d))
    Q = A + A.transpose(0, 2, 1)
    sigma = rng.uniform(0.1, 1.0, (B, d))
    bound = quadratic_max(g, Q, sigma)
    grid = np.stack(np.meshgrid(*[np.linspace(-1, 1, 21)] * d, indexing="ij"), -1).reshape(-1, d)
    s = grid[None] * sigma[:, None]
    values = np.einsum("bpk,bk->bp", s, g) + 0.5 * np.einsum("bpk,bkl,bpl->bp", s, Q, s)
    assert np.all(values.max(axis=1) <= bound * (1 + 1e-12) + 1e-12)  # (equal at a vertex, to rounding)
    concave = -(A @ A.transpose(0, 2, 1)) - np.eye(d)
    top = np.linalg.solve(concave, -g[..., None])[..., 0]  # g + Q s = 0
    wide = 2 * np.abs(top) + 0.1
    exact = 0.5 * np.einsum("bk,bk->b", g, -np.linalg.solve(concave, g[..., None])[..., 0])
    np.testing.assert_allclose(quadratic_max(g, concave, wide), exact, rtol=1e-9)


# -- the proof against brute force ------------------------------------------------------------------


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_the_bounds_are_above_a_dense_brute_force_on_random_models(seed, quick_proofs):
    """Random arms, gravity in any direction, random narrowed ranges and payload: every
    bound is at least the largest torque of 200,000 random poses, every value found is a
    real torque at its pose, and found + gap reaches the brute force's maximum."""
    rng = np.random.default_rng(seed)
    arm = random_model(rng, 6)
    ranges = {j: tuple(np.sort(rng.uniform(-3.5, 3.5, 2))) for j in range(6)}
    model = with_ranges(arm, ranges)
    family = payload_family(model, RigidBody(0.0, tuple(rng.uniform(-0.1, 0.1, 3))))
    joint_ranges, mass = JointRanges.of(model), float(rng.uniform(0, 5))
    extremes = family.extremes(mass, joint_ranges)
    torque = family.static_torque(mass)
    dense = dense_maxima(torque, joint_ranges, rng)
    scale = np.abs(dense).max()
    assert np.all(extremes.bounds >= dense - 1e-12 * scale)
    at_poses = torque(extremes.poses)
    n = model.n
    np.testing.assert_allclose(
        np.concatenate([np.diag(at_poses[:n]), -np.diag(at_poses[n:])]), extremes.values, rtol=1e-12, atol=1e-12 * scale
    )
    assert np.all(extremes.poses >= joint_ranges.lower - 1e-12) and np.all(extremes.poses <= joint_ranges.upper + 1e-12)
    assert np.all(extremes.values + (extremes.bounds - extremes.values) >= dense - 1e-12 * scale)


def test_long_chains_get_plain_interval_bounds():
    """Beyond MAX_JOINTS joints the harmonic sums grow too large: interval bounds, loose but
    proven."""
    rng = np.random.default_rng(14)
    model = random_model(rng, MAX_JOINTS + 1)
    family = payload_family(model, RigidBody())
    assert family.forms is None
    joint_ranges = JointRanges.of(model, count=256)
    extremes = family.extremes(0.0, joint_ranges)
    dense = dense_maxima(family.static_torque(0.0), joint_ranges, rng, count=20_000)
    assert np.all(np.isfinite(extremes.bounds)) and np.all(extremes.bounds >= dense - 1e-9)


# -- narrowed ranges and the verdicts ------------------------------------------------------------------


@pytest.fixture(scope="module")
def narrowed_model():
    return with_ranges(irb140(), NARROWED_RANGES, NARROWED_PAYLOAD)


def test_narrowed_ranges_find_the_true_worst_joint_5_torque(narrowed_model):
    model = narrowed_model
    limits = derive_torque_limits(model)
    pose = np.clip(FAR_POSE, *np.array([j.position_limits for j in model.joints]).T)
    there = gravity(model, pose)[4]
    assert there < -3.0656
    load = workspace_load(model, NARROWED_PAYLOAD, limits)
    assert load.torque[4] <= there  # the true worst: at least as far as FAR_POSE
    assert gravity(model, load.pose[4])[4] == pytest.approx(load.torque[4], rel=1e-12)
    assert load.gap[4] <= 2 * CERTIFY_RTOL * abs(load.torque[4])


def test_check_payload_calls_a_payload_over_a_limit_past_the_local_maximum(narrowed_model):
    """A joint-5 limit between the search's local maximum (3.0631 N m) and the true worst
    (3.0657 N m): the payload is over it there, and the check says so."""
    params = narrowed_model.to_params()
    params["joint_5.torque_limit"] = 3.0645
    model = RobotModel.from_params(params)
    check = check_payload(model, NARROWED_PAYLOAD)
    assert not check.ok and check.over == ["joint_5"]
    assert check.workspace.bound[4] > 3.0645


def test_the_default_model_is_proven_to_the_tolerance():
    model = irb140()
    limits = derive_torque_limits(model)
    gap = limits.rated_bound - np.abs(limits.rated_torque)
    assert np.all(gap >= 0) and np.all(gap <= 2 * CERTIFY_RTOL * np.maximum(np.abs(limits.rated_torque), 1e-3 * 290))
    check = check_payload(model, RigidBody(6.0), limits)
    assert check.ok  # the rated payload within its own limits: proven to within RTOL
    assert check.workspace.max_payload.gap == 0.0


def test_a_spent_budget_leaves_a_gap_and_the_verdict_says_unproven(monkeypatch):
    """With almost no budget the proof stops early: the bounds are loose but still bounds,
    the gap is reported, and a limit between the torque found and the bound is neither
    passed nor failed: UNPROVEN (a bound is never a torque)."""
    model, payload = irb140(), RigidBody(3.0, (0.05, 0.01, 0.1))  # a shape of its own: no proof remembered
    limits = derive_torque_limits(model)
    monkeypatch.setattr(certify, "EVALUATIONS", 0)  # one bound of the whole box per objective
    load = workspace_load(model, payload, limits, JointRanges.of(model, count=512))
    assert load.gap[1] > 1.0  # joint 2: 270 N m found, the bound of the whole box far above
    rng = np.random.default_rng(15)
    ranges = JointRanges.of(model)
    dense = np.abs(
        payload_family(model, payload).static_torque(3.0)(
            ranges.lower + rng.random((100_000, 6)) * (ranges.upper - ranges.lower)
        )
    )
    assert np.all(dense.max(axis=0) <= load.bound + 1e-9)
    params = model.to_params()
    for j in (0, 2, 3, 4, 5):  # the others above their bounds: proven within
        params[f"joint_{j + 1}.torque_limit"] = load.bound[j] + 1.0
    params["joint_2.torque_limit"] = abs(load.torque[1]) + 0.5 * load.gap[1]
    strict = RobotModel.from_params(params)
    check = check_payload(strict, payload, derive_torque_limits(strict), workspace=load)
    assert check.verdict == "UNPROVEN" and not check.ok, check.report()
    assert check.unproven == ["joint_2"] and check.over == []
    assert check.report().startswith(
        f"UNPROVEN: 3.000 kg not proven to fit: joint_2's worst static torque is proven only up to "
        f"{load.bound[1]:.3f} N m"
    )
    assert any(
        line.startswith("note: joint_2: worst static torque proven only up to") for line in check.report().splitlines()
    )
    best = load.max_payload  # none proven with so little: the search's mass is all gap
    assert best.gap > 0 and (math.isnan(best.mass) or best.mass + best.gap <= 2.31)
    assert "the proof's budget ran out" in check.report()
    for limit, verdict in ((0.99 * abs(load.torque[1]), "OVER-LIMIT"), (load.bound[1] + 1.0, "OK")):
        params["joint_2.torque_limit"] = limit  # below the torque found at a real pose; above the bound
        strict = RobotModel.from_params(params)
        assert check_payload(strict, payload, derive_torque_limits(strict), workspace=load).verdict == verdict
