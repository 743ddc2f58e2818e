"""sim_node started 5 s before its controller (id_node, computed torque), in real time, as
the demo starts them: the arm stays on its brakes (reset_hold 0) until id_node's first
command, then id_node holds it where it is. Without the brakes it falls some 0.85 rad."""

import numpy as np
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState

from .test_sim_node import POSE, sim_with_controller, stamp

BEFORE = 5.0  # s on the states' stamps: sim_node alone
AFTER = 1.0  # s of states after the first command
FALL = 0.01  # rad: far below a fall, far above computed torque's hold error


def test_the_arm_waits_on_its_brakes_for_a_controller_started_5_s_later():
    with sim_with_controller(reset_hold=0.0) as (harness, add_controller):
        states = harness.listen(JointState, "joint_states", 1000)
        assert harness.spin_until(lambda: states and stamp(states[-1]) - stamp(states[0]) >= BEFORE * 1e9, 120.0)
        assert all(msg.position.tolist() == POSE and not np.any(msg.effort) for msg in states)  # braked
        add_controller(
            [
                Parameter("effort_commands.enabled", value=True),
                Parameter("effort_commands.source", value="computed_torque"),
            ]
        )
        assert harness.spin_until(lambda: np.any(states[-1].effort), 60.0), "no command applied"
        commanded = next(stamp(msg) for msg in states if np.any(msg.effort))
        assert harness.spin_until(lambda: stamp(states[-1]) - commanded >= AFTER * 1e9, 60.0)
        moved = np.abs(np.array([msg.position for msg in states]) - POSE).max()
        assert moved < FALL, moved
