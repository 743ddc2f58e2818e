"""id_node's virtual force sensor in-process: an arm held still by its drives against gravity
and a known wrench on its flange (efforts = g(q) - J(q)^T F_true, both by Pinocchio) gives
external_wrench = F_true after 7/K s, on the IRB-140, the UR5 and the Panda, in the tip's
and the base's axes, named by the URDF's links and stamped like the input; at a singular
pose the estimate stays finite and /diagnostics says WARN."""

import numpy as np
import pinocchio as pin
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import WrenchStamped
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState

from irb140_dynamics.core import irb140
from irb140_dynamics.core.io.urdf import export_urdf, load_urdf
from irb140_dynamics.core.monitoring.wrench import SINGULAR_THRESHOLD, flange_wrench
from irb140_dynamics.nodes.id_node.node import IdNode

from ..support.ros_harness import running
from ..support.urdf_support import ARMS, arm_text, pinocchio_of

GAIN = 100.0  # 1/s: collision.observer_gain
DT = 0.001  # s: joint states at 1 kHz
SETTLED = round(7 / GAIN / DT) + 1  # samples: 7/K s after the first (the observer's lag below 0.1 %)
IRB140_TEXT = export_urdf(irb140())
CASES = {  # URDF text (None: the node's default parameters), base link, tip link
    "irb140": (None, "base_link", "flange"),
    "ur5": (arm_text("ur5"), "world", ARMS["ur5"][1]),
    "panda": (arm_text("panda"), "panda_link0", ARMS["panda"][1]),
}


def overrides(arm: str, frame: str) -> list[Parameter]:
    text, _, tip = CASES[arm]
    values = [Parameter("collision.observer_gain", value=GAIN), Parameter("external_wrench.frame", value=frame)]
    if text is not None:
        values += [
            Parameter("model.source", value="robot_description"),
            Parameter("model.tip_link", value=tip),
            Parameter("robot_description", value=text),
        ]
    return values


def reference(arm: str):
    """Pinocchio's model of the arm (its held joints locked) and the tip frame's id."""
    text, _, tip = CASES[arm]
    text = IRB140_TEXT if text is None else text
    pm = pinocchio_of(text, load_urdf(text, tip_link=tip).held_joints)
    return pm, pm.createData(), pm.getFrameId(tip)


def regular_pose(model, seed: int) -> np.ndarray:
    """A pose well away from singularities (J's smallest singular value over 2x the threshold)."""
    for q in np.random.default_rng(seed).uniform(-1.2, 1.2, (1000, model.n)):
        if flange_wrench(model, q, np.zeros(model.n)).smallest_singular_value > 2 * SINGULAR_THRESHOLD:
            return q
    raise AssertionError("no regular pose")


def held_efforts(arm: str, q, F_true, frame: str) -> np.ndarray:
    """What the drives give to hold q against gravity and F_true: g(q) - J(q)^T F_true."""
    pm, data, tip = reference(arm)
    J = pin.computeFrameJacobian(pm, data, q, tip, pin.LOCAL if frame == "tip" else pin.LOCAL_WORLD_ALIGNED)
    return pin.computeGeneralizedGravity(pm, data, q) - J.T @ F_true


def joint_state(names, t: float, q, effort) -> JointState:
    msg = JointState(name=list(names), position=[float(x) for x in q], velocity=[0.0] * len(q))
    msg.effort = [float(x) for x in effort]
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int(round((t % 1) * 1e9))
    return msg


def hold(harness, q, effort, start: float, samples: int) -> WrenchStamped:
    """``samples`` joint states of the arm held at q, 1 kHz from ``start`` s; the last wrench."""
    names = harness.node.settings.model.joint_names
    for k in range(samples):
        count = len(harness.wrenches)
        harness.joint_states.publish(joint_state(names, start + k * DT, q, effort))
        assert harness.spin_until(lambda: len(harness.wrenches) > count), "no external_wrench"
    return harness.wrenches[-1]


def started(harness):
    harness.wrenches = harness.listen(WrenchStamped, "external_wrench", 1000)
    harness.diagnostics = harness.listen(DiagnosticArray, "/diagnostics")
    harness.joint_states = harness.publisher(JointState, "joint_states")
    assert harness.spin_until(lambda: harness.node.settings is not None), "no model"
    assert harness.spin_until(lambda: harness.node._wrench_pub.subscribers > 0)
    return harness


@pytest.mark.parametrize("frame", ["tip", "base"])
@pytest.mark.parametrize("arm", list(CASES))
def test_a_known_wrench_on_a_held_arm_is_measured(arm, frame):
    rng = np.random.default_rng(len(arm) + len(frame))
    F_true = np.concatenate([rng.normal(0.0, 30.0, 3), rng.normal(0.0, 3.0, 3)])  # N, N m
    with running(IdNode, parameter_overrides=overrides(arm, frame)) as harness:
        started(harness)
        model = harness.node.settings.model
        q = regular_pose(model, seed=5)
        msg = hold(harness, q, held_efforts(arm, q, F_true, frame), 3.0, SETTLED)
    _, base, tip = CASES[arm]
    assert msg.header.frame_id == (tip if frame == "tip" else base)
    last = 3.0 + (SETTLED - 1) * DT
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (3, round((last % 1) * 1e9))
    f, m = msg.wrench.force, msg.wrench.torque
    force, torque = np.array([f.x, f.y, f.z]), np.array([m.x, m.y, m.z])
    force_error, torque_error = np.linalg.norm(force - F_true[:3]), np.linalg.norm(torque - F_true[3:])
    assert force_error <= 0.01 * np.linalg.norm(F_true[:3]) + 0.1, (force, F_true[:3])
    assert torque_error <= 0.01 * np.linalg.norm(F_true[3:]) + 0.02, (torque, F_true[3:])


def wrench_statuses(harness) -> list:
    return [s for d in harness.diagnostics for s in d.status if s.name.endswith(": external wrench")]


def test_at_a_singular_pose_the_wrench_is_finite_and_flagged():
    with running(IdNode, parameter_overrides=overrides("irb140", "tip")) as harness:
        started(harness)
        q = np.zeros(6)  # the IRB-140's wrist axes 4 and 6 in line
        push = np.array(
            [0.0, 0.0, 0.0, 2.0, 0.0, 0.01]
        )  # N m about the flange origin: partly along no direction J reaches
        msg = hold(harness, q, held_efforts("irb140", q, push, "tip"), 3.0, SETTLED)
        values = [msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z]
        values += [msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z]
        assert np.isfinite(values).all() and np.abs(values).max() < 1e3
        warned = lambda: [s for s in wrench_statuses(harness) if s.level == DiagnosticStatus.WARN]  # noqa: E731
        assert harness.spin_until(warned, timeout=30.0), [s.message for s in wrench_statuses(harness)]
        status = warned()[0]
    assert status.message.startswith("near a singularity") and f"< {SINGULAR_THRESHOLD:g}" in status.message


def test_the_frame_can_be_changed_while_running_and_a_bad_one_is_refused():
    with running(IdNode, parameter_overrides=overrides("irb140", "tip")) as harness:
        started(harness)
        q, F_true = regular_pose(harness.node.settings.model, seed=5), np.array([10.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        refused = harness.set_parameters([Parameter("external_wrench.frame", value="world")])[0]
        assert not refused.successful and "external_wrench.frame" in refused.reason
        assert harness.set_parameters([Parameter("external_wrench.frame", value="base")])[0].successful
        msg = hold(harness, q, held_efforts("irb140", q, F_true, "base"), 3.0, SETTLED)
    assert msg.header.frame_id == "base_link"
    assert abs(msg.wrench.force.x - 10.0) <= 0.2 and abs(msg.wrench.force.y) <= 0.2
