"""Computed-torque control on the true arm: MuJoCo's physics (sim.engine, the engine under
sim_node) stepped at 1 kHz, the command computed from each state and applied the next step
(one sample of delay, as id_node beside sim_node), along the demo's reference motion. The
exact model tracks within 1 mrad RMS per joint; the report's model does far worse. The
ROS path (id_node's commands, sim_node's stepping) has tests of its own."""

import numpy as np
import pytest

from irb140_dynamics.core import irb140, load_model
from irb140_dynamics.core.trajectories.reference import DEMO_CENTRE, computed_torque, swing
from irb140_dynamics.sim.engine import SimulatedArm

from ..support.paths import ROOT

TRUE_ARM = load_model(ROOT / "config" / "true_arm.yaml")
PERIOD = 8.0  # s: the demo's motion
RATE = 1000.0  # Hz
KP, KD = np.full(6, 400.0), np.full(6, 40.0)  # id_node's defaults


def tracking_rms(model, duration=PERIOD) -> np.ndarray:
    """RMS of q_ref - q per joint [rad] with ``model`` in the controller, the true arm simulated."""
    arm = SimulatedArm(TRUE_ARM, period=1.0 / RATE)
    arm.reset(DEMO_CENTRE)
    t = np.arange(int(duration * RATE)) / RATE
    Q, QD, QDD = swing(t, PERIOD)
    command, errors = np.zeros(6), []
    for q_ref, qd_ref, qdd_ref in zip(Q, QD, QDD):
        q, qd = arm.q.copy(), arm.qd.copy()
        errors.append(q_ref - q)
        arm.step(command)  # the command of the previous state: one sample late
        command = computed_torque(model, q, qd, q_ref, qd_ref, qdd_ref, KP, KD)
    return np.sqrt(np.mean(np.square(errors), axis=0))


def test_the_exact_model_tracks_within_a_milliradian():
    rms = tracking_rms(TRUE_ARM)
    assert np.all(rms < 1e-3), rms


@pytest.mark.parametrize("model", [irb140], ids=["report"])
def test_the_reports_model_tracks_the_true_arm_far_worse(model):
    exact, report = tracking_rms(TRUE_ARM, 2.0), tracking_rms(model(), 2.0)
    print(
        f"tracking error RMS [mrad], 2 s of the demo motion: exact model {np.round(exact * 1e3, 3).tolist()}, "
        f"report's model {np.round(report * 1e3, 2).tolist()}"
    )
    assert report.max() > 10 * exact.max()
