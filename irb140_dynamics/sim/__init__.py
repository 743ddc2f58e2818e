"""The simulated arm: a RobotModel as a MuJoCo model, stepped under applied torques.

May import: ``core``. No ROS here (``nodes.sim_node`` is the ROS side)."""

from irb140_dynamics.sim.engine import SimulatedArm
from irb140_dynamics.sim.mjcf import mjcf, mujoco_model

__all__ = ["SimulatedArm", "mjcf", "mujoco_model"]
