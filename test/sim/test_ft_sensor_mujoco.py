"""The wrist force/torque sensor in MuJoCo: the IRB-140 with a 2 kg tool
(CoM off the flange, a full inertia) behind a simulated sensor (MuJoCo's force and torque
sensors on a site at the flange), following a smooth motion under computed torque (the flange's
acceleration up to 2 m/s^2) and pushed on the tool by a hand: 20 N, reached and let go
over PUSH_RAMP (a step push is a step in the acceleration, which no estimate from joint
velocities follows at once: 2.6 N off for the first millisecond). MuJoCo's sensors give the wrench the parent
exerts on the tool; ours read the tool's on the sensor: the reading is minus MuJoCo's.

Checked: with MuJoCo's own accelerations the contact wrench is the push to round-off; as
id_node runs it (core.ft_sensor.stream: joint states at 500 Hz, qdd differentiated, readings
at 1 kHz matched to the nearest joint state) the push reads within 1 N and 0.1 N m and no
push within 0.3 N; and the tool's mass and CoM, and a bias, come back from rest readings."""

import mujoco
import numpy as np

from irb140_dynamics.core import RigidBody, irb140
from irb140_dynamics.core.ft_sensor.contact import contact_wrench
from irb140_dynamics.core.ft_sensor.load_estimation import estimate_ft_load
from irb140_dynamics.core.ft_sensor.stream import FtSensorStream
from irb140_dynamics.core.payload.mass_com_estimation import RestSample
from irb140_dynamics.sim.mjcf import mjcf

TOOL = RigidBody(2.0, (0.03, -0.02, 0.12), (0.012, 0.015, 0.008, 0.001, -0.002, 0.0015))
MODEL = irb140().with_payload(TOOL)
PERIOD, DURATION = 0.001, 1.6  # s
PUSH_START, PUSH_END, PUSH_RAMP = 0.5, 1.1, 0.2  # s
PUSH = 20.0 * np.array([0.6, -0.64, 0.48])  # N, base axes, 20 N
PUSHED_POINT = np.array([0.0, 0.05, 0.15])  # m, on the tool, flange frame
Q0 = np.array([0.2, -0.3, 0.4, 0.5, 0.9, -0.3])
AMPLITUDE, FREQUENCY = np.array([0.4, 0.3, 0.3, 0.6, 0.5, 0.8]), 0.4  # rad, Hz
KP, KD = 400.0, 40.0  # 1/s^2, 1/s


def sensed_arm():
    """The MuJoCo model with the tool body named and force and torque sensors at the flange."""
    lines = mjcf(MODEL, timestep=PERIOD, friction=False).splitlines()
    tool = max(k for k, line in enumerate(lines) if "<body " in line and "name=" not in line)
    lines[tool] = lines[tool].replace("<body ", '<body name="tool" ')
    lines.insert(tool + 1, '<site name="ft"/>')
    end = lines.index("</mujoco>")
    lines[end:end] = ['<sensor><force site="ft"/><torque site="ft"/></sensor>']
    mj_model = mujoco.MjModel.from_xml_string("\n".join(lines))
    return mj_model, mujoco.MjData(mj_model), mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_BODY, "tool")


def reference(t):
    w = 2 * np.pi * FREQUENCY
    return Q0 + AMPLITUDE * np.sin(w * t), AMPLITUDE * w * np.cos(w * t), -AMPLITUDE * w * w * np.sin(w * t)


def push_share(t):
    """The push's share of its 20 N at t [s]: raised-cosine ramps up and down, held between."""
    rising, falling = (t - PUSH_START) / PUSH_RAMP, (PUSH_END - t) / PUSH_RAMP
    return 0.5 - 0.5 * np.cos(np.pi * np.clip(min(rising, falling), 0.0, 1.0))


def simulate():
    """Per step: (t, q, qd, qdd, reading, the true contact wrench in base axes about the flange)."""
    mj_model, data, tool = sensed_arm()
    inverse = mujoco.MjData(mj_model)
    q_ref, qd_ref, _ = reference(0.0)
    data.qpos[:], data.qvel[:] = q_ref, qd_ref
    rows = []
    for step in range(round(DURATION / PERIOD)):
        t = step * PERIOD
        q_ref, qd_ref, qdd_ref = reference(t)
        inverse.qpos[:], inverse.qvel[:] = data.qpos, data.qvel
        inverse.qacc[:] = qdd_ref + KD * (qd_ref - data.qvel) + KP * (q_ref - data.qpos)
        mujoco.mj_inverse(mj_model, inverse)
        data.qfrc_applied[:] = inverse.qfrc_inverse
        mujoco.mj_kinematics(mj_model, data)
        R, origin = data.xmat[tool].reshape(3, 3), data.xpos[tool]  # the tool body's frame is the flange's
        point = origin + R @ PUSHED_POINT
        force = push_share(t) * PUSH
        data.xfrc_applied[tool] = np.concatenate([force, np.cross(point - data.xipos[tool], force)])
        mujoco.mj_forward(mj_model, data)
        truth = np.concatenate([force, np.cross(point - origin, force)])
        rows.append((t, data.qpos.copy(), data.qvel.copy(), data.qacc.copy(), -data.sensordata.copy(), truth))
        mujoco.mj_step(mj_model, data)
    return rows


def test_a_push_on_the_tool_reads_as_it_was_and_no_push_reads_nothing():
    rows = simulate()
    exact = np.array([contact_wrench(MODEL, q, qd, qdd, w, frame="base") - truth for _, q, qd, qdd, w, truth in rows])
    assert np.max(np.abs(exact)) < 1e-6
    stream = FtSensorStream()
    stream.use(MODEL, "flange", "base", None, 20.0)
    errors, pushed = [], []
    for step, (t, q, qd, _, reading, truth) in enumerate(rows):
        if step % 2 == 0:  # joint states at 500 Hz
            stream.note(t, q, qd)
        errors.append(stream.contact(t, reading) - truth)
        pushed.append(push_share(t) > 0.0)
    errors, pushed = np.array(errors), np.array(pushed)
    force, torque = np.linalg.norm(errors[:, :3], axis=1), np.linalg.norm(errors[:, 3:], axis=1)
    print(
        f"pushed: force error <= {force[pushed].max():.3f} N, torque <= {torque[pushed].max():.4f} N m; "
        f"not pushed: force <= {force[~pushed].max():.3f} N"
    )
    assert force[pushed].max() < 1.0 and torque[pushed].max() < 0.1
    assert force[~pushed].max() < 0.3


def test_bias_mass_and_com_come_back_from_mujoco_rests():
    mj_model, data, _ = sensed_arm()
    bias = np.array([4.0, -3.0, 2.0, 0.3, 0.2, -0.4])
    samples = []
    for wrist in ([0.0, 0.5, 0.0], [1.2, -0.8, 0.5], [-0.7, 1.2, 1.7], [0.4, 0.9, -1.5]):
        q = np.array([0.3, -0.4, 0.5, *wrist])
        data.qpos[:], data.qvel[:], data.qacc[:] = q, 0.0, 0.0
        mujoco.mj_inverse(mj_model, data)  # the torques that hold the arm still
        data.qfrc_applied[:] = data.qfrc_inverse
        mujoco.mj_forward(mj_model, data)
        assert np.max(np.abs(data.qacc)) < 1e-6
        samples.append(RestSample(q, -data.sensordata.copy() + bias, 1))
    estimate = estimate_ft_load(MODEL, samples)
    assert abs(estimate.mass - TOOL.mass) < 1e-6
    np.testing.assert_allclose(estimate.com, TOOL.com, atol=1e-6)
    np.testing.assert_allclose(estimate.bias, bias, atol=1e-6)
