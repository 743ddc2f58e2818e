"""Load identification on simulated arms: a payload identified from a MuJoCo recording.

Two arms, the IRB-140 (config/true_arm.yaml: friction and rotor inertia on every joint) and
the UR5 of ``support.simulated_ur5`` (its URDF, friction, rotor inertia), each carrying a
payload with an off-axis CoM and a full inertia tensor (principal axes turned away from the
flange's), follow the wrist motion `excitation --payload` makes
(``optimise_payload_excitation``) in MuJoCo; the recorded efforts carry noise of 1 % of
each joint's peak. ``fit_payload`` is given the arm's own model (links, friction, rotor
inertia: the params file) and must find the mass within 2 %, the CoM within 5 mm and each
principal moment of inertia about the CoM within 10 % or 0.002 kg m^2, whichever is larger.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from irb140_dynamics.core import RigidBody, rnea_batch
from irb140_dynamics.core.io.params_file import load_model
from irb140_dynamics.core.model.joints import Placement
from irb140_dynamics.core.model.rigid_body import inertia_matrix
from irb140_dynamics.identification.consistent import pseudo_inertia
from irb140_dynamics.identification.excitation import check_limits
from irb140_dynamics.identification.least_squares import Estimate
from irb140_dynamics.identification.payload import (
    _nearest_physical,
    fit_payload,
    payload_of,
    payload_parameters,
    payload_regressor,
)
from irb140_dynamics.identification.payload_excitation import (
    MAX_PAYLOAD_DURATION,
    MIN_WRIST_TRAVEL,
    optimise_payload_excitation,
    with_assumed_accelerations,
    wrist,
)
from irb140_dynamics.identification.recording import RecordingError

from ..support.paths import ROOT
from ..support.simulated_ur5 import simulate, true_ur5, write_csv

pytestmark = pytest.mark.slow  # each arm: an optimised excitation and 20 s of MuJoCo at 500 Hz
NOISE = 0.01  # of each joint's peak effort
PERIODS = 2


def tool(mass, com, moments, angles) -> RigidBody:
    """A payload of principal moments ``moments`` turned by ``angles`` (xyz Euler, rad)."""
    R = Rotation.from_euler("xyz", angles).as_matrix()
    I = R @ np.diag(moments) @ R.T
    return RigidBody(mass, com, (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]))


ARMS = {
    # arm, payload, feedback gains of the simulated controller (per joint, kg m^2), period [s]
    # (given: the design's choice of it is test_load_any_arm's)
    "irb140": (
        lambda: load_model(ROOT / "config" / "true_arm.yaml"),
        tool(3.5, (0.06, -0.04, 0.09), (0.012, 0.02, 0.03), (0.4, -0.3, 0.7)),
        (8.0, 8.0, 3.0, 0.3, 0.3, 0.1),
        7.5,
    ),
    "ur5": (true_ur5, tool(2.0, (0.04, -0.03, 0.06), (0.006, 0.009, 0.0125), (-0.5, 0.2, 0.9)), None, 3.0),
}


@pytest.fixture(scope="module", params=sorted(ARMS))
def recorded(request, tmp_path_factory):
    """(arm without payload, true payload, excitation, (t, Q, QD, TAU), CSV path)."""
    make, payload, gains, period = ARMS[request.param]
    arm = make()
    excitation = optimise_payload_excitation(arm, period=period, iterations=10)
    duration = PERIODS * excitation.trajectory.period
    recording = simulate(arm.with_payload(payload), excitation.trajectory, duration, noise=NOISE, gains=gains)
    path = write_csv(tmp_path_factory.mktemp(request.param) / "payload.csv", arm.joint_names, *recording)
    return arm, payload, excitation, recording, path


def test_the_payload_is_identified_within_the_issues_tolerances(recorded):
    arm, truth, _, _, path = recorded
    fit = fit_payload(arm, path)
    found = fit.payload
    assert found.mass == pytest.approx(truth.mass, rel=0.02)
    assert np.linalg.norm(np.subtract(found.com, truth.com)) < 0.005
    moments = np.linalg.eigvalsh(inertia_matrix(found.inertia))
    true_moments = np.linalg.eigvalsh(inertia_matrix(truth.inertia))
    assert np.all(np.abs(moments - true_moments) <= np.maximum(0.1 * true_moments, 0.002)), (moments, true_moments)
    # the printed standard deviations are honest: the errors are a few of them at most
    assert abs(found.mass - truth.mass) < 5 * fit.std["mass"]
    assert np.all(np.abs(np.subtract(found.com, truth.com)) < 5 * fit.std["com"] + 1e-4)
    # physically consistent: mass > 0, inertia about the CoM positive definite
    assert found.mass > 0 and moments.min() > 0 and np.linalg.eigvalsh(pseudo_inertia(fit.phi)).min() > 0
    assert np.all(fit.excitation > 0.1)


def test_the_excitation_moves_only_the_wrist_within_limits_and_30_s(recorded):
    arm, _, excitation, (t, Q, _, _), _ = recorded
    trajectory = excitation.trajectory
    assert trajectory.period * PERIODS <= MAX_PAYLOAD_DURATION
    assert check_limits(with_assumed_accelerations(arm), trajectory, 100.0) == []  # the limits it states
    planned = trajectory.evaluate(np.linspace(0.0, trajectory.period, 2000))[0]
    moving = wrist(arm)
    held = np.setdiff1d(np.arange(arm.n), moving)
    assert np.all(np.ptp(planned[:, moving], axis=0) > MIN_WRIST_TRAVEL)
    assert np.all(np.ptp(planned[:, held], axis=0) == 0.0)
    assert np.all(np.ptp(Q[:, held], axis=0) < 0.02)  # the simulated arm's held joints: still
    assert np.isfinite(excitation.condition_number) and excitation.condition_number < 20


def test_a_motion_of_one_wrist_joint_is_refused_naming_what_it_misses(recorded, tmp_path):
    """Turning only the last joint about its axis shows no inertia about the axes across it."""
    arm, payload, excitation, _, _ = recorded
    trajectory = excitation.trajectory
    t = np.arange(int(trajectory.period * 500)) / 500.0
    Q, QD, QDD = trajectory.evaluate(t)
    Q[:, :-1], QD[:, :-1], QDD[:, :-1] = Q[0, :-1], 0.0, 0.0
    tau = rnea_batch(arm.with_payload(payload), Q, QD, QDD)
    path = write_csv(tmp_path / "last_joint.csv", arm.joint_names, t, Q, QD, tau)
    with pytest.raises(RecordingError, match=r"does not excite the payload's Ixx, Ixy, Iyy \(flange frame"):
        fit_payload(arm, path)


@pytest.mark.parametrize("make", [true_ur5, lambda: load_model(ROOT / "config" / "true_arm.yaml")])
def test_the_payload_regressor_gives_the_payloads_torques(make):
    """tau(arm with payload) = tau_arm + Y_p phi, also for a flange turned and moved in the last link."""
    from dataclasses import replace

    payload = tool(2.5, (0.03, 0.05, -0.02), (0.01, 0.02, 0.025), (0.3, 0.2, -0.4))
    rng = np.random.default_rng(3)
    for arm in (make(), replace(make(), flange=Placement((0.01, -0.02, 0.05), (0.3, -0.2, 0.5)))):
        Q, QD, QDD = (rng.normal(size=(20, arm.n)) for _ in range(3))
        Y, tau_arm = payload_regressor(arm.with_payload(payload), Q, QD, QDD)
        expected = rnea_batch(arm.with_payload(payload), Q, QD, QDD)
        assert tau_arm + Y @ payload_parameters(payload) == pytest.approx(expected, abs=1e-9)
        assert tau_arm == pytest.approx(rnea_batch(arm.with_payload(RigidBody()), Q, QD, QDD), abs=1e-9)
    assert payload_of(payload_parameters(payload)).inertia == pytest.approx(payload.inertia, abs=1e-12)


def test_an_unphysical_estimate_becomes_the_nearest_physical_payload():
    physical = payload_parameters(tool(2.0, (0.05, 0.0, 0.1), (0.01, 0.012, 0.015), (0.1, 0.2, 0.3)))
    covariance = np.diag(np.r_[1e-4, [1e-6] * 3, [1e-6] * 6])
    kept, misfit = _nearest_physical(Estimate(physical, covariance, np.ones(6), 1.0, 100))
    assert misfit == 0.0 and np.array_equal(kept, physical)
    unphysical = physical.copy()
    unphysical[9] = 0.5 * physical[0] * (physical[1] ** 2 + physical[2] ** 2) / physical[0] ** 2  # Izz too small
    assert np.linalg.eigvalsh(pseudo_inertia(unphysical)).min() < 0
    nearest, misfit = _nearest_physical(Estimate(unphysical, covariance, np.ones(6), 1.0, 100))
    assert misfit > 0 and np.linalg.eigvalsh(pseudo_inertia(nearest)).min() > 0
    body = payload_of(nearest)  # validated: mass > 0, inertia positive definite, triangle inequality
    moments = np.linalg.eigvalsh(inertia_matrix(body.inertia))
    assert body.mass > 0 and moments.min() > 0 and moments[0] + moments[1] >= moments[2]
    assert nearest[0] == pytest.approx(unphysical[0], rel=0.05)  # moved mostly where it was cheap


def test_a_wrist_motion_too_small_for_the_noise_is_refused_with_the_deviations(tmp_path):
    """The same motion at a tenth of its size: its accelerations leave the inertia about the
    flange's x and y axes to the noise (standard deviations above 5 % of m |c|^2)."""
    from dataclasses import replace

    arm = load_model(ROOT / "config" / "true_arm.yaml")
    payload = tool(3.0, (0.05, 0.03, 0.08), (0.012, 0.02, 0.03), (0.4, -0.3, 0.7))
    trajectory = optimise_payload_excitation(arm, iterations=0).trajectory
    t = np.arange(0.0, trajectory.period, 0.004)

    def recording(size):
        motion = replace(trajectory, a=trajectory.a * size, b=trajectory.b * size)
        Q, QD, QDD = motion.evaluate(t)
        tau = rnea_batch(arm.with_payload(payload), Q, QD, QDD)
        tau += np.random.default_rng(0).normal(size=tau.shape) * NOISE * np.abs(tau).max(axis=0)
        return write_csv(tmp_path / f"size_{size}.csv", arm.joint_names, t, Q, QD, tau)

    assert fit_payload(arm, recording(1.0)).payload.mass == pytest.approx(payload.mass, rel=0.02)
    with pytest.raises(
        RecordingError, match=r"excitation --payload` \(a weak motion\): the payload's Ixx \(\+- [0-9.e-]+ kg m\^2\)"
    ):
        fit_payload(arm, recording(0.1))
