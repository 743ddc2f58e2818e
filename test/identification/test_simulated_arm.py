"""Identification of a simulated public arm from its URDF: the UR5 in MuJoCo (``support.simulated_ur5``).

The prior is the UR5's URDF with link masses off by factors within [0.5, 1.5] (one of them
at a bound) and no friction; the true arm has viscous and Coulomb friction (MuJoCo's dry
friction) and rotor inertia. Checked: the held-out RMS torque error on moving samples, the
"unphysical" warning (silent on the clean arm, firing on torques no arm can make), and
samples where a joint is stuck (held by dry friction) kept out of the fit.
"""

import numpy as np
import pytest

from irb140_dynamics.core.regressor import inertial_parameters
from irb140_dynamics.identification.pipeline import IdentificationSettings, identify
from irb140_dynamics.identification.report import summary

from ..support.simulated_ur5 import ARMATURE, COULOMB, VISCOUS, excitation, prior_ur5, simulate, true_ur5, write_csv

pytestmark = pytest.mark.slow
DURATION = 24.0  # s: three periods of the excitation


@pytest.fixture(scope="module")
def arm():
    return true_ur5()


@pytest.fixture(scope="module")
def prior():
    model, factors = prior_ur5(0)
    assert np.abs(factors - 1.0).max() == pytest.approx(0.5) and np.all(np.abs(factors - 1.0) <= 0.5)
    return model


@pytest.fixture(scope="module")
def clean(arm, tmp_path_factory):
    """(t, Q, QD, TAU) of the arm along its excitation, and the CSV of it."""
    recording = simulate(arm, excitation(arm, 1), DURATION)
    path = write_csv(tmp_path_factory.mktemp("ur5") / "clean.csv", arm.joint_names, *recording)
    return recording, path


def test_identified_from_its_urdf_within_5_percent_and_no_false_unphysical_warning(arm, prior, clean):
    result = identify(prior, clean[1])
    peak = result.held_out.peak
    identified, before = result.rms("identified") / peak, result.rms("prior") / peak
    assert np.all(identified <= 0.05), identified
    assert np.all(before > 3 * identified)  # the prior was far off: the data did the work
    assert result.physical.physical and result.fit.consistent
    printed = summary(result)
    assert "WARNING" not in printed and "the data agree with a physical arm" in printed
    # friction and armature of the true arm, from torques MuJoCo made
    n = arm.n
    joints = result.fit.pi[10 * n :].reshape(n, 3)
    assert joints[:, 0] == pytest.approx(VISCOUS, rel=0.05)
    assert joints[:, 1] == pytest.approx(COULOMB, rel=0.05)
    separable = np.isin(10 * n + 3 * np.arange(n) + 2, result.base.independent)  # not joints 1, 2: with Izz
    assert separable.sum() >= 3
    assert joints[separable, 2] == pytest.approx(ARMATURE[separable], rel=0.1, abs=0.005)


def test_unphysical_warning_fires_on_torques_no_arm_can_make(arm, prior, clean, tmp_path):
    (t, Q, QD, TAU), _ = clean
    flipped = TAU * np.where(np.arange(arm.n) == 2, -1.0, 1.0)  # the elbow's torque sign flipped
    result = identify(prior, write_csv(tmp_path / "flipped.csv", arm.joint_names, t, Q, QD, flipped))
    assert not result.physical.physical and result.physical.chi2 > 2 * result.physical.bound
    assert "WARNING: the data ask for an unphysical arm" in summary(result)


def test_a_stuck_joint_does_not_bias_the_fit(arm, prior, tmp_path):
    """Joint 2 held still for 8 s of 24: dry friction holds it at any torque within its
    Coulomb level, which the model does not describe. Its rows are left out (|qd| below
    the threshold), so its friction comes out right; fitted with them (threshold 0), the
    friction is off by 10 % and more."""
    recording = simulate(arm, excitation(arm, 1), DURATION, stuck=(1, 4.0, 12.0))
    path = write_csv(tmp_path / "stuck.csv", arm.joint_names, *recording)
    stuck_samples = np.abs(recording[2][:, 1]) < 1e-3
    assert stuck_samples.mean() > 0.3
    n = arm.n

    def joint_2_friction(min_speed):
        result = identify(prior, path, IdentificationSettings(min_speed=min_speed))
        return result.fit.pi[10 * n + 3 : 10 * n + 5], result.rms("identified")[1] / result.held_out.peak[1]

    (viscous, coulomb), error = joint_2_friction(None)
    assert viscous == pytest.approx(VISCOUS[1], rel=0.02) and coulomb == pytest.approx(COULOMB[1], rel=0.02)
    assert error < 0.005
    (viscous, coulomb), error = joint_2_friction(0.0)  # the stuck rows in: the friction biased
    assert abs(viscous / VISCOUS[1] - 1) > 0.1 and abs(coulomb / COULOMB[1] - 1) > 0.05 and error > 0.01


def test_the_prior_is_the_urdf_with_masses_off(arm, prior):
    masses = inertial_parameters(prior)[0 : 10 * arm.n : 10] / inertial_parameters(arm)[0 : 10 * arm.n : 10]
    assert np.all((masses >= 0.5 - 1e-12) & (masses <= 1.5 + 1e-12)) and not np.allclose(masses, 1.0)
