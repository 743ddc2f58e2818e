"""A wrist force/torque sensor freed of its tool, against physics identities: the tool's
wrench on the sensor is what RNEA's joint torques say it is (the payload's share of tau,
through the sensor's Jacobian), so a tool alone reads no contact in any pose and motion and
a known push is given back; the bias and the tool's mass and CoM come back from noisy rest
readings; too few orientations are refused."""

from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics.core import RigidBody, irb140, rnea
from irb140_dynamics.core.ft_sensor.contact import contact_wrench, sensor_mount, tool_wrench
from irb140_dynamics.core.ft_sensor.load_estimation import estimate_ft_load
from irb140_dynamics.core.ft_sensor.stream import FtSensorStream
from irb140_dynamics.core.io.urdf.reader import load_urdf
from irb140_dynamics.core.io.urdf.writer import export_urdf, exported_carried
from irb140_dynamics.core.kinematics import flange_jacobian, flange_motion, flange_pose
from irb140_dynamics.core.payload.mass_com_estimation import EstimationError, RestSample

from ..support.common import random_urdf_model

TOOL = RigidBody(2.0, (0.03, -0.02, 0.12), (0.012, 0.015, 0.008, 0.001, -0.002, 0.0015))


def arms():
    """The IRB-140 (DH: link_6's frame is not the flange's) and a random 6-joint URDF-form arm."""
    return [irb140().with_payload(TOOL), random_urdf_model(np.random.default_rng(3), 6).with_payload(TOOL)]


def skew(r):
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def wrench_from_torques(model, q, mount, tau_tool):
    """The wrench on the sensor (base axes, about its origin) whose joint torques are
    -tau_tool: the arm holds what the tool exerts (tau = rnea with tool - rnea without)."""
    pose, J = flange_pose(model, q), flange_jacobian(model, q)
    r = pose[:3, :3] @ mount[:3, 3]  # flange origin -> sensor origin
    J_o = np.vstack([J[:3] - skew(r) @ J[3:], J[3:]])
    return -np.linalg.solve(J_o.T, tau_tool)


def in_sensor(model, q, mount, wrench_base):
    R = flange_pose(model, q)[:3, :3] @ mount[:3, :3]
    return np.concatenate([R.T @ wrench_base[:3], R.T @ wrench_base[3:]])


def test_flange_motion_is_the_derivative_of_the_jacobian_velocity():
    urdf_arm = arms()[1]
    sliding = tuple(replace(j, kind="prismatic") if i in (1, 3) else j for i, j in enumerate(urdf_arm.joints))
    for model in [*arms(), replace(urdf_arm, joints=sliding)]:
        q, qd, qdd = np.random.default_rng(0).normal(size=(3, 6))
        pose, w, alpha, a = flange_motion(model, q, qd, qdd)
        h = 1e-5

        def twist(t):
            return flange_jacobian(model, q + qd * t + qdd * t * t / 2) @ (qd + qdd * t)

        np.testing.assert_allclose(w, twist(0.0)[3:], atol=1e-12)
        np.testing.assert_allclose(np.concatenate([a, alpha]), (twist(h) - twist(-h)) / (2 * h), atol=1e-7)
        np.testing.assert_allclose(pose, flange_pose(model, q), atol=1e-15)


@pytest.mark.parametrize("link", ["flange", "link_6"])
def test_a_tool_alone_reads_no_contact_and_a_push_is_given_back(link):
    rng = np.random.default_rng(1)
    for model in arms():
        mount = sensor_mount(model, link, exported_carried(model))
        bare = model.with_payload(RigidBody())
        for _ in range(10):
            q, qd, qdd = rng.normal(size=6), rng.normal(size=6), rng.normal(size=(6)) * 3
            tool_base = wrench_from_torques(model, q, mount, rnea(model, q, qd, qdd) - rnea(bare, q, qd, qdd))
            reading = in_sensor(model, q, mount, tool_base)
            np.testing.assert_allclose(tool_wrench(model, q, qd, qdd, mount)[0], reading, atol=1e-9)
            np.testing.assert_allclose(contact_wrench(model, q, qd, qdd, reading, mount), 0.0, atol=1e-9)
            push = np.concatenate([rng.normal(size=3) * 20, rng.normal(size=3) * 2])  # base axes, about o
            bias = rng.normal(size=6)
            pushed = in_sensor(model, q, mount, tool_base + push) + bias
            np.testing.assert_allclose(contact_wrench(model, q, qd, qdd, pushed, mount, bias, "base"), push, atol=1e-8)


def test_a_hanging_tool_reads_its_weight():
    model = irb140().with_payload(RigidBody(2.0))
    q = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    reading, R = tool_wrench(model, q, np.zeros(6), np.zeros(6))
    np.testing.assert_allclose(R @ reading[:3], [0.0, 0.0, -2.0 * 9.81], atol=1e-12)


def test_links_of_the_exported_and_the_read_urdf_place_the_sensor_alike():
    model = irb140()
    read = load_urdf(export_urdf(model))
    q = np.random.default_rng(2).normal(size=6)
    for link in ("flange", "link_6"):
        ours = flange_pose(model, q) @ sensor_mount(model, link, exported_carried(model))
        theirs = flange_pose(read.model, q) @ sensor_mount(read.model, link, read.carried)
        np.testing.assert_allclose(ours, theirs, atol=1e-12)
    with pytest.raises(ValueError, match=r"^ft_sensor.link: 'link_5' is moved by joint joint_5, not by joint_6"):
        sensor_mount(model, "link_5", exported_carried(model))
    with pytest.raises(
        ValueError, match=r"^ft_sensor.link: no link 'tool0' that the arm's joints move \(links: flange, "
    ):
        sensor_mount(model, "tool0", read.carried)


def rest_samples(model, mount, poses, bias, rng, noise=(0.05, 0.005)):
    """A rest per pose: the static reading (RNEA's gravity torques through J) plus bias and noise."""
    bare = model.with_payload(RigidBody())
    samples = []
    for q in poses:
        zero = np.zeros(6)
        static = wrench_from_torques(model, q, mount, rnea(model, q, zero, zero) - rnea(bare, q, zero, zero))
        reading = in_sensor(model, q, mount, static) + bias + np.repeat(noise, 3) * rng.normal(size=6)
        samples.append(RestSample(np.asarray(q, dtype=float), reading, 100))
    return samples


def test_bias_mass_and_com_come_back_from_noisy_rests():
    rng = np.random.default_rng(4)
    for model in arms():
        mount = sensor_mount(model, "link_6", exported_carried(model))
        bias = np.array([3.0, -2.0, 5.0, 0.3, -0.2, 0.1])
        poses = rng.uniform(-1.5, 1.5, size=(8, 6))
        estimate = estimate_ft_load(model, rest_samples(model, mount, poses, bias, rng), mount)
        assert abs(estimate.mass - TOOL.mass) < 0.02 * TOOL.mass
        assert np.max(np.abs(np.array(estimate.com) - TOOL.com)) < 0.005
        np.testing.assert_allclose(estimate.bias, bias, atol=0.05)
        assert estimate.mass_std < 0.05 and estimate.poses == 8
        assert np.all(np.abs(np.array(estimate.com) - TOOL.com) < 5 * np.array(estimate.com_std) + 1e-4)


def test_too_few_orientations_are_refused():
    model = irb140().with_payload(TOOL)
    mount, rng = np.eye(4), np.random.default_rng(5)
    base = [0.0, -0.3, 0.4, 0.5, 0.8, 0.2]
    turned = [[q1, *base[1:]] for q1 in (0.0, 0.7, -0.9, 1.4)]  # joint 1 turns about gravity: one orientation
    other = [0.0, -0.3, 0.4, -0.6, 1.2, 0.9]
    for poses, count in ((turned, 1), (turned + [other], 2)):
        with pytest.raises(EstimationError, match=rf"^the sensor rested in {count} orientation\(s\) relative to"):
            estimate_ft_load(model, rest_samples(model, mount, poses, np.zeros(6), rng), mount)


def test_readings_of_the_opposite_sign_or_no_gravity_are_refused_and_an_empty_tool_is_none():
    """A sensor reporting the wrench on the tool (each reading negated) gives -2 kg with a
    small deviation: refused, saying the convention; no tool gives ~0 kg, too light for a CoM;
    a model without gravity is refused saying so (not "more orientations needed")."""
    model = irb140().with_payload(TOOL)
    rng, poses = np.random.default_rng(8), np.random.default_rng(9).uniform(-1.5, 1.5, size=(6, 6))
    negated = [replace(s, effort=-s.effort) for s in rest_samples(model, np.eye(4), poses, np.zeros(6), rng)]
    with pytest.raises(
        EstimationError,
        match=r"^the tool's mass came out negative \(-(1\.99|2\.00)\d \+- 0\.0\d\d kg\): the readings must",
    ):
        estimate_ft_load(model, negated, np.eye(4))
    empty = estimate_ft_load(irb140(), rest_samples(irb140(), np.eye(4), poses, np.zeros(6), rng, (0.0, 0.0)))
    assert abs(empty.mass) < 1e-9 and empty.com is None
    weightless = replace(model, gravity=(0.0, 0.0, 0.0))
    with pytest.raises(EstimationError, match=r"^the model's gravity is zero: a tool's load shows at rest only"):
        estimate_ft_load(weightless, rest_samples(weightless, np.eye(4), poses, np.zeros(6), rng))


def test_the_stream_matches_readings_to_the_nearest_joint_state_and_estimates_from_its_rests():
    model = irb140().with_payload(TOOL)
    stream = FtSensorStream()
    stream.use(model, "flange", "sensor", None, 20.0)
    with pytest.raises(EstimationError, match="^the sensor rested in 0 orientation"):
        stream.estimate()
    bias, rng = np.array([1.0, 2.0, -3.0, 0.1, 0.0, -0.2]), np.random.default_rng(6)
    poses = [[0.0, -0.3, 0.4, a, b, c] for a, b, c in ((0.0, 0.5, 0.0), (1.2, -0.8, 0.5), (-0.7, 1.2, 1.7))]
    t = 0.0
    for q in poses:
        sample = rest_samples(model, np.eye(4), [q], bias, rng, noise=(0.0, 0.0))[0]
        for _ in range(60):  # 0.6 s at rest, joint states and readings at 100 Hz, readings 4 ms late
            stream.note(t, np.array(q), np.zeros(6))
            stream.contact(t + 0.004, sample.effort)
            t += 0.01
        stream.note(t + 0.5, np.array(q), np.full(6, 0.5))  # moving to the next pose: the rest ends
        stream.contact(t + 0.5, sample.effort)
        t += 1.0
    np.testing.assert_allclose(stream.contact(t - 1.01, sample.effort), bias, atol=1e-9)  # contact = bias before
    estimate = stream.estimate()
    assert estimate.poses == 3 and abs(estimate.mass - TOOL.mass) < 1e-6
    np.testing.assert_allclose(stream.contact(t - 1.01, sample.effort), 0.0, atol=1e-6)  # the bias in use now
    for bad, kind in (([np.nan] * 6, "not_finite"), ([1e6, 0, 0, 0, 0, 0], "absurd_wrench")):
        with pytest.raises(ValueError, match=f"^{kind}: "):
            stream.contact(t, bad)
    with pytest.raises(ValueError, match=r"^no_joint_state: the nearest joint state is 1 s from the reading"):
        stream.contact(t + 0.5, sample.effort)
    stream.note(t + 1.0, np.array(q), np.full(6, 1e160))  # finite, but its w x (w x r) is not
    with np.errstate(all="raise"), pytest.raises(ValueError, match=r"^not_finite_contact: no finite contact wrench"):
        stream.contact(t + 1.0, sample.effort)


def test_the_stream_refuses_a_bad_frame_or_link_or_turns_off_when_told():
    model, stream = irb140().with_payload(TOOL), FtSensorStream()
    with pytest.raises(EstimationError, match="^the force/torque sensor is off: no model yet, or ft_sensor.link empty"):
        stream.estimate()  # a node waiting for its URDF
    stream.use(model, "flange", "sensor", None, 20.0)
    with pytest.raises(ValueError, match=r"^ft_contact_wrench.frame: must be one of sensor, base; got 'tool'$"):
        stream.use(model, "flange", "tool", None, 20.0)
    assert stream.model is model and stream.frame == "sensor"  # nothing changed
    refused = stream.use(model, "link_2", "sensor", None, 20.0, strict=False)
    assert (
        refused.startswith("ft_sensor.link: 'link_2' is moved by joint joint_2, not by joint_6")
        and stream.model is None
    )
    assert refused.endswith("; the force/torque sensor is off")


def test_a_reading_in_another_links_frame_is_refused_and_the_sensors_own_or_none_accepted():
    model, stream = irb140().with_payload(TOOL), FtSensorStream()
    stream.use(model, "flange", "sensor", None, 20.0)
    q = np.array([0.0, -0.3, 0.4, 0.0, 0.5, 0.0])
    stream.note(0.0, q, np.zeros(6))
    reading = tool_wrench(model, q, np.zeros(6), np.zeros(6))[0] + np.array([5.0, 0.0, -2.0, 0.0, 0.3, 0.0])
    for frame_id in ("", "flange", "/flange"):
        np.testing.assert_allclose(stream.contact(0.0, reading, frame_id), [5.0, 0.0, -2.0, 0.0, 0.3, 0.0], atol=1e-9)
    for frame_id in ("link_6", "base_link", "flange_sensor"):
        with pytest.raises(
            ValueError, match=rf"^wrong_frame: reading in frame '{frame_id}', the sensor is on 'flange'$"
        ):
            stream.contact(0.0, reading, frame_id)
