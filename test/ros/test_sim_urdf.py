"""sim_node with its true arm from a URDF (model.source robot_description), in-process."""

import numpy as np
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, String

from irb140_dynamics.core import gravity
from irb140_dynamics.core.io.urdf import load_urdf
from irb140_dynamics.nodes.sim_node.node import SimNode

from ..support.paths import URDF_DATA
from ..support.ros_harness import running
from ..support.urdf_support import ARMS, arm_text
from .test_sim_node import states_after_reset
from .test_urdf_nodes import from_urdf, node_and_description_publisher

POSE = [0.3, -1.0, 1.2, -0.5, 0.8, 0.1]  # rad, UR5: away from its limits; it falls from here


def test_a_urdf_arm_is_simulated_and_held_by_its_own_gravity():
    tip = ARMS["ur5"][1]
    model = load_urdf(arm_text("ur5"), tip_link=tip).model
    overrides = from_urdf(
        tip, model__urdf_file=str(URDF_DATA / "ur5.urdf"), initial_positions=POSE, command_timeout=0.0
    )
    with running(SimNode, parameter_overrides=overrides) as sim:
        sim.states = sim.listen(JointState, "joint_states", 1000)
        sim.commands = sim.publisher(Float64MultiArray, "effort_commands")
        states = states_after_reset(sim, 300, gravity(model, POSE))
        assert list(states[0].name) == list(model.joint_names)
        assert np.abs(np.array([msg.position for msg in states]) - POSE).max() < 1e-6


def test_without_a_model_it_waits_then_runs_the_one_that_comes():
    with node_and_description_publisher(SimNode, from_urdf(ARMS["ur5"][1])) as sim:
        states = sim.listen(JointState, "joint_states", 1000)
        sim.spin_for(0.3)
        assert not states and sim.node.reset() is False
        sim.description.publish(String(data=arm_text("ur5")))
        assert sim.spin_until(lambda: len(states) > 100)
        assert len(states[-1].name) == 6 and states[-1].name[0] == "shoulder_pan_joint"
