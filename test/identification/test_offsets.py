"""Torque offsets per joint (``--offsets``, off by default): eliminated from the normal
equations (``NormalEquations.centred``), fitted, and applied on held-out data."""

import numpy as np
import pytest

from irb140_dynamics.core import rnea_batch
from irb140_dynamics.identification.least_squares import NormalEquations
from irb140_dynamics.identification.pipeline import IdentificationSettings, identify

from ..support.simulated_ur5 import excitation, true_ur5, write_csv

OFFSETS = np.array([0.5, -1.0, 0.3, 0.0, 0.2, -0.1])  # N m


def test_centred_sums_are_least_squares_with_a_free_offset_per_joint():
    rng = np.random.default_rng(4)
    K, n, P = 300, 3, 5
    Y, tau = rng.normal(size=(K, n, P)), rng.normal(size=(K, n)) + [1.0, -2.0, 0.5]
    use = rng.uniform(size=(K, n)) > 0.2
    sums = NormalEquations(n, P)
    sums.add(Y, tau, use)
    centred = sums.centred()
    pi = np.linalg.solve(centred.A.sum(axis=0), centred.b.sum(axis=0))
    # the same from the rows, with a column of ones per joint
    rows, targets = [], []
    for j in range(n):
        for k in np.flatnonzero(use[:, j]):
            rows.append(np.concatenate([Y[k, j], np.eye(n)[j]]))
            targets.append(tau[k, j])
    solution = np.linalg.lstsq(np.array(rows), np.array(targets), rcond=None)[0]
    assert pi == pytest.approx(solution[:P], rel=1e-10, abs=1e-12)
    assert sums.offsets(pi) == pytest.approx(solution[P:], rel=1e-10, abs=1e-12)
    residuals = [np.array(rows)[:, :P] @ pi + np.array(rows)[:, P:] @ solution[P:] - np.array(targets)]
    by_joint = [np.sum(r**2) for r in np.split(residuals[0], np.cumsum(use.sum(axis=0))[:-1])]
    assert sums.rss(pi, solution[P:]) == pytest.approx(by_joint, rel=1e-9)
    assert centred.rss(pi) == pytest.approx(by_joint, rel=1e-9)


@pytest.fixture(scope="module")
def biased(tmp_path_factory):
    """The UR5's torques (rnea on the true arm) with a constant offset per joint and 0.1 %
    noise (the offsets of joints 2 and 3, which carry gravity, are the least determined)."""
    arm = true_ur5()
    t = np.arange(int(24.0 * 200.0)) / 200.0
    Q, QD, QDD = excitation(arm, 1).evaluate(t)
    tau = rnea_batch(arm, Q, QD, QDD)
    tau += OFFSETS + np.random.default_rng(8).normal(size=tau.shape) * 0.001 * np.abs(tau).max(axis=0)
    return arm, write_csv(tmp_path_factory.mktemp("offsets") / "biased.csv", arm.joint_names, t, Q, QD, tau)


def test_offsets_are_fitted_when_asked_and_off_by_default(biased):
    arm, path = biased
    with_offsets = identify(arm, path, IdentificationSettings(offsets=True))
    assert with_offsets.offsets == pytest.approx(OFFSETS, abs=0.05)
    peak = with_offsets.held_out.peak
    assert np.all(with_offsets.rms("identified") < 0.01 * peak)
    default = identify(arm, path)
    assert default.offsets is None
    worst = int(np.argmax(np.abs(OFFSETS) / peak))
    assert default.rms("identified")[worst] > 3 * with_offsets.rms("identified")[worst]
