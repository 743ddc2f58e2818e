"""Record -> identify -> track better, on MuJoCo's physics: the true arm (config/true_arm.yaml)
is driven along an excitation trajectory under computed-torque control with the report's
model; its joint states (positions, velocities, applied efforts) are recorded as an .mcap
bag; `identify` fits the model to the recording; then the demo's (different) motion is
tracked with the report's model and with the identified one."""

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from irb140_dynamics.core import irb140
from irb140_dynamics.core.trajectories.reference import computed_torque
from irb140_dynamics.identification.excitation import optimise_excitation
from irb140_dynamics.identification.pipeline import identify
from irb140_dynamics.sim.engine import SimulatedArm

from ..core.test_computed_torque_loop import KD, KP, TRUE_ARM, tracking_rms
from ..support.synthetic_arm import Samples, joint_state_messages, write_bag

RATE = 500.0  # Hz: the loop and the recording
PERIODS = 2


def record(controller, excitation) -> Samples:
    """The true arm along the excitation under computed torque with ``controller``."""
    trajectory = excitation.trajectory
    t = trajectory.times(RATE, PERIODS)
    Q, QD, QDD = trajectory.evaluate(t)
    arm = SimulatedArm(TRUE_ARM, period=1.0 / RATE)
    arm.reset(Q[0])
    command = np.zeros(6)
    positions, velocities, efforts = [], [], []
    for q_ref, qd_ref, qdd_ref in zip(Q, QD, QDD):
        q, qd = arm.q.copy(), arm.qd.copy()
        positions.append(q)
        velocities.append(qd)
        efforts.append(command)  # the torque applied from this state on (a driver reports it with it)
        arm.step(command)
        command = computed_torque(controller, q, qd, q_ref, qd_ref, qdd_ref, KP, KD)  # next step's: one late
    efforts = np.array(efforts)
    return Samples(t, np.array(positions), np.array(velocities), efforts, efforts)


@pytest.mark.slow
def test_identification_from_the_simulated_arm_tracks_five_times_better(tmp_path):
    report = irb140()
    excitation = optimise_excitation(report, iterations=3, seed=2)
    samples = record(report, excitation)
    typestore = get_typestore(Stores.ROS2_JAZZY)
    bag = write_bag(tmp_path / "run", joint_state_messages(samples, report.joint_names, True, typestore))
    result = identify(report, bag)
    before, after = tracking_rms(report, 4.0), tracking_rms(result.identified, 4.0)
    print(
        f"tracking error RMS [mrad] on the demo motion: report's model {np.round(before * 1e3, 2).tolist()}, "
        f"identified {np.round(after * 1e3, 3).tolist()}"
    )
    assert np.sqrt(np.mean(after**2)) * 5 <= np.sqrt(np.mean(before**2))
    assert np.all(after <= before)
