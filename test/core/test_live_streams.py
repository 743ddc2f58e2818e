"""What id_node computes per joint state, without ROS: the torques of a stream (feed-forward,
gravity, commands, a reference followed in time), collisions from the observer's residual,
the flange wrench's nearness to a singularity, and where the markers go."""

import math

import numpy as np
import pytest

from irb140_dynamics.core import RigidBody, gravity, irb140, mass_matrix, rnea
from irb140_dynamics.core.kinematics import flange_pose, joint_origins
from irb140_dynamics.core.model.joint_order import BadMessage
from irb140_dynamics.core.monitoring import display
from irb140_dynamics.core.monitoring.collision import CollisionMonitor
from irb140_dynamics.core.monitoring.observer import MomentumObserver
from irb140_dynamics.core.monitoring.wrench import SINGULAR_THRESHOLD, WrenchStream, flange_wrench
from irb140_dynamics.core.trajectories.reference import Trajectory, computed_torque
from irb140_dynamics.core.trajectories.tracking import Gains, TorqueStream

MODEL = irb140()
Q = np.array([0.3, -0.4, 0.5, 0.2, 0.7, 0.1])
QD = np.array([0.1, -0.2, 0.3, 0.0, 0.1, -0.1])
ZEROS = np.zeros(6)
GAINS = Gains(np.full(6, 400.0), np.full(6, 40.0))


def stream(mode="zero", source=None, timeout=0.0):
    torques = TorqueStream()
    assert torques.use(MODEL, mode, 20.0, timeout, source, GAINS)
    return torques


def never():
    raise AssertionError("the clock is read only while a reference is held")


def test_measured_states_give_the_core_torques_and_the_observer_terms():
    tau, g, command, reference, terms = stream(source="feedforward").torques(1.0, Q, QD, False, never)
    assert list(tau) == rnea(MODEL, Q, QD, ZEROS).tolist() and list(g) == gravity(MODEL, Q).tolist()
    assert command is tau and reference is None and terms is None
    tau, g, _, _, terms = stream().torques(1.0, Q, QD, True, never)  # efforts: one pass, the observer's terms
    np.testing.assert_allclose(tau, rnea(MODEL, Q, QD, ZEROS), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(g, gravity(MODEL, Q), rtol=1e-12, atol=1e-12)
    p, _ = terms
    np.testing.assert_allclose(p, mass_matrix(MODEL, Q) @ QD, rtol=1e-12, atol=1e-12)  # p = M(q) qd


def test_a_reference_is_followed_in_time_and_computed_torque_commands_it():
    torques = stream(source="computed_torque", timeout=0.5)
    q_end = Q + 0.2
    trajectory = Trajectory(np.array([0.0, 1.0]), np.array([Q, q_end]), np.zeros((2, 6)), None)
    torques.follow(trajectory, start=10.0)
    tau, _, command, reference, _ = torques.torques(0.0, ZEROS, ZEROS, False, lambda: 10.5)
    np.testing.assert_allclose(reference[0], Q + 0.1, rtol=1e-12)  # halfway, by linear interpolation
    np.testing.assert_allclose(tau, rnea(MODEL, Q + 0.1, ZEROS, ZEROS), rtol=1e-12, atol=1e-12)
    expected = computed_torque(MODEL, ZEROS, ZEROS, Q + 0.1, ZEROS, None, GAINS.kp, GAINS.kd)
    np.testing.assert_allclose(command, expected, rtol=1e-12, atol=1e-12)
    assert torques.torques(0.0, ZEROS, ZEROS, False, lambda: 11.4)[3] is not None  # the end held until the timeout
    _, _, command, reference, _ = torques.torques(0.0, Q, ZEROS, False, lambda: 11.6)
    assert reference is None  # let go: the position measured then is held
    np.testing.assert_allclose(command, computed_torque(MODEL, Q, ZEROS, Q, ZEROS, None, GAINS.kp, GAINS.kd))
    _, _, command, _, _ = torques.torques(0.0, Q + 0.1, ZEROS, False, lambda: 12.0)
    np.testing.assert_allclose(command, computed_torque(MODEL, Q + 0.1, ZEROS, Q, ZEROS, None, GAINS.kp, GAINS.kd))


def test_absurd_states_are_refused_and_a_held_reference_the_new_model_cannot_take_is_let_go():
    torques = stream(mode="differentiate", source="feedforward")
    torques.torques(1.0, Q, ZEROS, False, never)
    with pytest.raises(BadMessage) as refused:
        torques.torques(1.0 + 1e-9, Q, np.full(6, 1e300), False, never)
    assert refused.value.kind in ("not_finite_acceleration", "non_finite_torques")
    assert torques.differentiator.qdd == [0.0] * 6  # started afresh
    qd = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 3e153])  # finite torques with the bare arm only
    torques.follow(Trajectory(np.array([0.0]), Q[None], qd[None], None), start=0.0)
    heavy = MODEL.with_payload(RigidBody(1e6, (0.5, 0.5, 0.5), (1e6, 1e6, 1e6, 0.0, 0.0, 0.0)))
    assert not torques.use(heavy, "zero", 20.0, 0.0, None, GAINS)
    assert torques.tracker.trajectory is None
    with pytest.raises(BadMessage, match="non_finite_torques"):
        torques.follow(Trajectory(np.array([0.0]), Q[None], qd[None], None), start=0.0)


def test_collisions_are_the_residual_over_thresholds_reported_with_their_peaks():
    monitor = CollisionMonitor()
    monitor.use(MODEL, 100.0, [0.0, 5.0, 0.0, 0.0, 0.0, 0.0])
    observer = MomentumObserver(MODEL, 100.0)
    g = gravity(MODEL, Q)
    push = np.array([0.0, 20.0, 0.0, 0.0, 0.0, 0.0])
    for k in range(60):  # 20 N m on joint 2, seen through the observer's lag
        effort = g - (push if k < 40 else 0.0)
        r = monitor.update(1.0 + k * 1e-3, Q, ZEROS, effort, g)
        assert r == pytest.approx(observer.advance(1.0 + k * 1e-3, Q, ZEROS, effort, g), abs=1e-12)
        if k == 39:
            assert monitor.colliding == [1] and abs(r[1]) > 5.0
            peak = abs(r[1])
    assert monitor.colliding == [] and abs(r[1]) < 5.0  # r decays as exp(-K t): under 5 N m after 20 ms
    collided, message, values = monitor.report()
    assert collided and message == f"collision since last report: joint_2 {peak:.2f} N m"
    assert values["joint_2 peak |external torque| since last report [N m]"] == f"{peak:.3f}"
    assert monitor.report() == (
        False,
        "no collision",
        {f"{n} external torque [N m]": f"{x:.3f}" for n, x in zip(MODEL.joint_names, r)},
    )
    monitor.update(1.5, Q, ZEROS, g, g)  # a gap of more than 0.1 s
    assert monitor.restarted == "gap" and monitor.residual == [0.0] * 6


def test_the_wrench_stream_reports_the_nearest_singularity_since_the_last_report():
    watch = WrenchStream()
    assert watch.report()[0] is False
    stretched, bent = np.zeros(6), np.array([0.0, 0.3, 0.5, 0.0, 0.8, 0.0])
    r = [1.0, 2.0, 3.0, 0.5, 0.2, 0.1]
    watch.note(MODEL, stretched, r)
    near = watch.estimate("tip")
    assert near.smallest_singular_value < SINGULAR_THRESHOLD
    np.testing.assert_allclose(near.vector, flange_wrench(MODEL, stretched, r, "tip").vector, rtol=1e-12)
    watch.note(MODEL, bent, r)
    warned, message, values = watch.report()
    sigma = flange_wrench(MODEL, bent, r).smallest_singular_value
    assert sigma > SINGULAR_THRESHOLD and warned and message.startswith("near a singularity since the last report")
    assert values["smallest singular value of J, now"] == f"{sigma:.4f}"
    assert watch.report()[:2] == (False, f"smallest singular value of J {sigma:.4f}")  # a new period


def test_the_arm_picture_puts_joints_payload_and_force_where_the_kinematics_do():
    model = irb140(payload=RigidBody(3.0, (0.0, 0.02, 0.05)))
    external = np.array([1.0, -2.0, 3.0, 0.5, 0.2, 0.1])
    picture = display.arm_picture(model, Q, gravity(model, Q), None, external)
    np.testing.assert_allclose(picture.origins, joint_origins(model, Q), atol=1e-12)
    pose = flange_pose(model, Q)
    np.testing.assert_allclose(picture.payload, pose[:3, :3] @ model.payload.com + pose[:3, 3], atol=1e-12)
    force = flange_wrench(model, Q, external, "base").force
    np.testing.assert_allclose(picture.arrow_end, pose[:3, 3] + display.ARROW_PER_NEWTON * force, atol=1e-12)
    assert picture.loads == [None] * 6  # no limits known
    origins = joint_origins(model, Q)
    shared = [sum(np.linalg.norm(origins[j] - origins[i]) < display.SAME_PLACE for i in range(j)) for j in range(6)]
    assert picture.earlier == shared and max(shared) == 1  # the IRB-140: joint 4 at joint 3's place, 6 at 5's
    assert picture.diameters == [display.JOINT_DIAMETER * display.NESTED**k for k in shared]
    with pytest.raises(ValueError, match="must be finite"):
        display.arm_picture(model, [math.nan] * 6, ZEROS)
    huge = display.arm_picture(model, Q, ZEROS, None, np.full(6, 1e300))  # the arrow saturates, finite
    assert np.linalg.norm(np.subtract(huge.arrow_end, huge.flange)) == pytest.approx(display.MAX_ARROW)
