"""Fuzz test of both nodes in-process (seeded, bounded): random joint states, references and
parameter sets, valid and invalid, in both acceleration modes.

Invariants: the node stays alive and reports no error of its own; an invalid input gives no
output (and changes nothing); a valid one gives exactly the core's torques (rnea, gravity,
check_payload); a refused parameter set leaves the model in force, an accepted one puts
RobotModel.from_params of all the parameters in force. Most messages go straight into the
callbacks (thousands per second); a share goes through DDS and the executor.
"""

import math
import time

import numpy as np
import pytest
from rclpy.exceptions import ParameterNotDeclaredException
from rclpy.parameter import Parameter
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState

from irb140_dynamics.core import RobotModel, check_payload, gravity, rnea
from irb140_dynamics.nodes.id_node.node import IdNode
from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode

from ..support.common import full_sweep
from ..support.fuzz_inputs import Fuzzer, parameter_set
from ..support.ros_harness import running

BUDGET = 2.5  # s of fuzzing per node and mode, at most, once MIN_MESSAGES are done
# id_node's: MIN_MESSAGES and a short while more in the suite, BUDGET with IRB140_SWEEP=full
ID_NODE_BUDGET = BUDGET if full_sweep() else 1.0
MIN_MESSAGES = 400  # per node and mode, at least, however slow the machine: the counts below hold
MESSAGES = 800  # per node and mode, at most
PARAMETER_EVERY = 30  # messages between two parameter sets
THROUGH_DDS_EVERY = 15  # one message in this many goes through DDS and the executor


class Recorder:
    """Stands in for a publisher: keeps a copy of the efforts of what is published."""

    def __init__(self):
        self.efforts = []

    def publish(self, msg):
        if isinstance(msg, bytes):  # id_node publishes its torques serialized
            msg = deserialize_message(msg, JointState)
        self.efforts.append(list(msg.effort))

    subscribers = 1  # a subscriber listens: id_node publishes only then (see ros.runtime.listened)


def held_point(node):
    """The first point of the trajectory id_node follows, as (q, qd, qdd or None) lists."""
    trajectory = node.stream.tracker.trajectory
    qdd = None if trajectory.qdd is None else trajectory.qdd[0].tolist()
    return trajectory.q[0].tolist(), trajectory.qd[0].tolist(), qdd


def core_torques(function, model, *state):
    """The core's torques, or None when it has none finite there (a ValueError or inf/nan)."""
    try:
        tau = function(model, *state)
    except ValueError:
        return None
    return tau if np.isfinite(tau).all() else None


def apply_parameters(harness, params):
    node = harness.node
    before = node.settings
    try:
        result = node.set_parameters_atomically(params)
    except ParameterNotDeclaredException:
        return False, before
    harness.settle()
    return result.successful, before


def check_parameters(harness, params, valid):
    """Apply a random set; the invariants of refusal and acceptance."""
    node = harness.node
    accepted, before = apply_parameters(harness, params)
    assert accepted == valid, (params, valid)
    values = node.parameters.values()
    if accepted:
        assert node.settings.model == RobotModel.from_params(values)
    else:
        assert node.settings is before
    return accepted


@pytest.mark.parametrize("mode", ["zero", "differentiate"])
def test_fuzz_id_node(mode):
    fuzz = Fuzzer(seed=8 if mode == "zero" else 9)
    overrides = [Parameter("acceleration.mode", value=mode), Parameter("reference_timeout", value=0.0)]
    with running(IdNode, parameter_overrides=overrides) as harness:
        node = harness.node
        inbox = harness.listen(JointState, "feedforward_torques")
        publisher = harness.publisher(JointState, "joint_states")
        direct_ff, direct_g = Recorder(), Recorder()
        real = node._feedforward_pub, node._gravity_pub
        held = None  # the reference the node must hold: (q, qd, qdd or None)
        deadline = time.monotonic() + ID_NODE_BUDGET
        counts = {"valid": 0, "dropped": 0, "dds": 0, "accepted": 0, "refused": 0}
        for k in range(MESSAGES):
            if k >= MIN_MESSAGES and time.monotonic() > deadline:
                break
            if k % PARAMETER_EVERY == PARAMETER_EVERY - 1:
                counts["accepted" if check_parameters(harness, *parameter_set(fuzz.rng)) else "refused"] += 1
                model = node.settings.model
                if held is not None and core_torques(rnea, model, held[0], held[1], held[2] or [0.0] * 6) is None:
                    held = None  # let go: the new model gives no finite torques there
                assert (node.stream.tracker.trajectory is None) == (held is None)
            if fuzz.rng.random() < 0.1:
                ref = fuzz.reference()
                node._on_reference(ref.msg)
                if ref.state == ("clear",):
                    held = None
                elif ref.state is not None:
                    q, qd, qdd = ref.state
                    if core_torques(rnea, node.settings.model, q, qd, qdd or [0.0] * 6) is not None:
                        held = ref.state
                assert (node.stream.tracker.trajectory is None) == (held is None)
                if held is not None:
                    assert held_point(node) == (held[0], held[1], held[2])
            item = fuzz.joint_state()
            model = node.settings.model
            through_dds = k % THROUGH_DDS_EVERY == 0
            if through_dds:
                node._feedforward_pub, node._gravity_pub = real
                before, received = len(inbox), node.counts["joint_states.received"]
                published = node.counts["torques.published"]
                publisher.publish(item.msg)
                assert harness.spin_until(lambda: node.counts["joint_states.received"] > received)
                if node.counts["torques.published"] > published:  # then its torques come, however late
                    assert harness.spin_until(lambda: len(inbox) > before)
                harness.spin_for(0.02)  # and nothing more
                outputs = [msg.effort.tolist() for msg in inbox[before:]]
                node._feedforward_pub, node._gravity_pub = direct_ff, direct_g
                counts["dds"] += 1
            else:
                node._feedforward_pub, node._gravity_pub = direct_ff, direct_g
                before = len(direct_ff.efforts)
                node._on_joint_state(serialize_message(item.msg) if k % 2 else item.msg)  # as DDS gives it, or not
                outputs = direct_ff.efforts[before:]
            assert not any(key.endswith(".errors") for key in node.counts), dict(node.counts)
            if item.state is None:
                assert outputs == [], (item.msg, outputs)
                counts["dropped"] += 1
                continue
            q, qd = item.state
            qdd = node.stream.differentiator.qdd if mode == "differentiate" else [0.0] * 6
            q_ff, qd_ff, qdd_ff = (held[0], held[1], held[2] or qdd) if held is not None else (q, qd, qdd)
            tau, g = core_torques(rnea, model, q_ff, qd_ff, qdd_ff), core_torques(gravity, model, q)
            if tau is None or g is None or not all(map(math.isfinite, qdd)):
                assert outputs == [], (item.msg, outputs)
                counts["dropped"] += 1
                continue
            assert outputs == [tau.tolist()], (item.msg, outputs, tau)
            if not through_dds:
                assert direct_g.efforts[-1] == g.tolist()
            counts["valid"] += 1
        node._feedforward_pub, node._gravity_pub = real
        assert counts["valid"] > 100 and counts["dropped"] > 50 and counts["dds"] > 10, counts
        assert counts["accepted"] > 3 and counts["refused"] > 3, counts


def test_fuzz_payload_check_node():
    fuzz = Fuzzer(seed=10)
    overrides = [Parameter("diagnostics.period", value=0.0)]
    with running(PayloadCheckNode, parameter_overrides=overrides) as harness:
        node = harness.node
        # The first analysis may outlast the node's STARTUP_WAIT on a busy machine: until it is
        # done the node has no settings and keeps no joint state. Fuzz the node once it is ready.
        harness.settle()
        assert node.settings is not None, node.parameters.status()
        state = None
        deadline = time.monotonic() + BUDGET
        for k in range(MESSAGES // 3):
            if time.monotonic() > deadline:
                break
            if k % (PARAMETER_EVERY // 2) == 0:
                check_parameters(harness, *parameter_set(fuzz.rng, model_structure=False))
                model = node.settings.model
                if state is not None and (
                    core_torques(rnea, model, state[0], state[1], [0.0] * 6) is None
                    or core_torques(gravity, model, state[0]) is None
                ):
                    state = None
            item = fuzz.joint_state()
            node._on_joint_state(item.msg)
            model = node.settings.model
            if (
                item.state is not None
                and core_torques(rnea, model, *item.state, [0.0] * 6) is not None
                and core_torques(gravity, model, item.state[0]) is not None
            ):
                state = item.state
            assert (node.state is None) == (state is None)
            if state is not None:
                assert (list(node.state.q), list(node.state.qd)) == state
            if k % 10 == 0:
                result, _ = node.check()
                settings = node.settings
                q, qd = state if state is not None else (None, None)
                expected = check_payload(
                    settings.model,
                    settings.model.payload,
                    settings.analysis.limits,
                    q,
                    qd,
                    workspace=settings.analysis.workspace,
                )
                assert result.report() == expected.report()
                assert "nan" not in result.report()
            assert not any(key.endswith(".errors") for key in node.counts), dict(node.counts)
