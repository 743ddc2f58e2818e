"""id_node's kernels native from the first message: made ready at startup and with each new
model before it is in force, the log saying native or Python; a compile longer than the
node's bound leaves the Python form answering meanwhile."""

from __future__ import annotations

import numpy as np
import pytest
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState

from irb140_dynamics import native
from irb140_dynamics.core import gravity
from irb140_dynamics.core.codegen.kernels import kernels_of
from irb140_dynamics.core.trajectories import stream_settings as id_settings
from irb140_dynamics.core.trajectories.stream_settings import KERNELS, kernels_text
from irb140_dynamics.nodes.id_node.node import IdNode

from ..support.ros_harness import running

needs_a_compiler = pytest.mark.skipif(not native.enabled(), reason="no C compiler (or IRB140_NATIVE=0)")


def natives(model) -> list[bool]:
    kernels = kernels_of(model)
    return [kernels.kernel(name).native is not None for name in KERNELS]


@needs_a_compiler
def test_the_kernels_are_native_before_the_first_message_and_after_a_model_change():
    with running(IdNode) as harness:
        settings = harness.node.settings
        assert settings.kernels.native and all(natives(settings.model)), settings.kernels
        assert kernels_text(settings.kernels).startswith("kernels: native")
        # a new arm (another moment of inertia: other code), checked and compiled off the executor
        inertia = [0.2, 0.328536, 0.328536, 0.0, 0.0, 0.0]
        harness.set_parameters([Parameter("joint_2.link.inertia", value=inertia)])
        changed = harness.node.settings
        assert list(changed.model.joints[1].link.inertia) == inertia
        assert changed.kernels is not settings.kernels and changed.kernels.native, changed.kernels
        assert all(natives(changed.model))


@needs_a_compiler
def test_a_compile_past_the_bound_leaves_the_python_form_answering_and_says_so(monkeypatch):
    monkeypatch.setattr(id_settings, "NATIVE_WAIT", 0.0)
    # an arm no test has compiled yet: a moment of inertia the payload's regrouping does not
    # reach (a link's mass would be an input of k, the same code)
    inertia = [float(np.random.default_rng().uniform(0.1, 0.6)), 0.328536, 0.328536, 0.0, 0.0, 0.0]
    with running(IdNode) as harness:
        gravity_torques = harness.listen(JointState, "gravity_torques")
        states = harness.publisher(JointState, "joint_states")
        harness.set_parameters([Parameter("joint_2.link.inertia", value=inertia)])
        settings = harness.node.settings
        assert list(settings.model.joints[1].link.inertia) == inertia
        assert not settings.kernels.native and settings.kernels.compiling, settings.kernels
        assert "Python form for now" in kernels_text(settings.kernels)
        q = [0.1, -0.7, 0.4, 0.2, -0.3, 0.5]
        msg = JointState(name=list(settings.model.joint_names), position=q, velocity=[0.0] * 6)
        states.publish(msg)
        assert harness.spin_until(lambda: gravity_torques), "no torques from the Python form"
        np.testing.assert_allclose(gravity_torques[-1].effort, gravity(settings.model, np.array(q)), rtol=1e-12)


def test_without_native_code_the_log_says_python(monkeypatch):
    monkeypatch.setenv("IRB140_NATIVE", "0")
    with running(IdNode) as harness:
        kernels = harness.node.settings.kernels
        assert not kernels.native and not kernels.compiling
        assert kernels_text(kernels).startswith("kernels: Python form (")


@needs_a_compiler
@pytest.mark.parametrize("mode", ["zero", "differentiate"])
def test_joint_states_are_answered_by_the_native_kernels(monkeypatch, mode):
    """The torques of every joint state come from the C kernels, never from their Python
    form (which a state in another form than the native one takes would fall back to)."""
    with running(IdNode, parameter_overrides=[Parameter("acceleration.mode", value=mode)]) as harness:
        model = harness.node.settings.model
        kernels = kernels_of(model)
        python_calls = []
        for kernel in (kernels.rnea_with_friction, kernels.gravity_torques):
            assert kernel.native is not None
            monkeypatch.setattr(kernel, "used", lambda kernel=kernel: python_calls.append(kernel))
        feedforward = harness.listen(JointState, "feedforward_torques")
        gravity_torques = harness.listen(JointState, "gravity_torques")
        states = harness.publisher(JointState, "joint_states")
        q = np.array([0.2, -0.5, 0.3, 0.1, 0.6, -0.2])
        for k in range(20):
            msg = JointState(name=list(model.joint_names), position=q.tolist(), velocity=[0.1 * k] * 6)
            msg.header.stamp.sec, msg.header.stamp.nanosec = 3, k * 1_000_000
            states.publish(msg)
            harness.spin_for(0.002)
        assert harness.spin_until(lambda: len(feedforward) >= 10 and len(gravity_torques) >= 10)
    assert python_calls == []
    np.testing.assert_allclose(gravity_torques[-1].effort, gravity(model, q), rtol=1e-12)
