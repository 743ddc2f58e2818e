"""The simulated arm: a RobotModel as a MuJoCo model, stepped under applied torques. No ROS here."""

from .engine import SimulatedArm
from .mjcf import mjcf, mujoco_model

__all__ = ["SimulatedArm", "mjcf", "mujoco_model"]
