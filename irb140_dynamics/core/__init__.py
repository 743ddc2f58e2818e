"""The dynamics core: models, kinematics, dynamics and payloads. No ROS in here.

>>> from irb140_dynamics.core import irb140, gravity
>>> gravity(irb140(), [0, -1.5707963267948966, 1.5707963267948966, 0, 0, 0]).round(3)
array([  0.   , 243.382,  79.156,  -0.   ,   2.43 ,   0.   ])
"""

from irb140_dynamics.core.codegen.kernels import Kernels, kernels_of
from irb140_dynamics.core.derivatives import (
    DERIVATIVE_KERNELS,
    forward_dynamics_derivatives,
    inverse_mass_matrix,
    rnea_derivatives,
)
from irb140_dynamics.core.dynamics import (
    Preparation,
    coriolis,
    coriolis_batch,
    coriolis_matrix,
    forward_dynamics,
    forward_dynamics_batch,
    gravity,
    gravity_batch,
    mass_matrix,
    mass_matrix_batch,
    prepare,
    rnea,
    rnea_batch,
)
from irb140_dynamics.core.io.params_file import load_model, read_parameter_file
from irb140_dynamics.core.kinematics import (
    dh_transform,
    flange_jacobian,
    flange_pose,
    link_frames,
    link_jacobian,
    link_pose,
)
from irb140_dynamics.core.model.irb140 import irb140
from irb140_dynamics.core.model.joints import DH, Friction, Joint, Placement
from irb140_dynamics.core.model.rigid_body import ModelError, RigidBody
from irb140_dynamics.core.model.robot_model import Mimic, RobotModel
from irb140_dynamics.core.payload import (
    RATED_PAYLOAD,
    MaxPayload,
    PayloadCheck,
    TorqueLimits,
    WorkspaceLoad,
    check_payload,
    derive_torque_limits,
    max_payload_at,
    workspace_load,
)

__all__ = [
    "DERIVATIVE_KERNELS",
    "DH",
    "Preparation",
    "Friction",
    "Joint",
    "Kernels",
    "MaxPayload",
    "Mimic",
    "ModelError",
    "PayloadCheck",
    "Placement",
    "RATED_PAYLOAD",
    "RigidBody",
    "RobotModel",
    "TorqueLimits",
    "WorkspaceLoad",
    "check_payload",
    "coriolis",
    "coriolis_batch",
    "coriolis_matrix",
    "derive_torque_limits",
    "dh_transform",
    "flange_jacobian",
    "flange_pose",
    "forward_dynamics",
    "forward_dynamics_batch",
    "forward_dynamics_derivatives",
    "gravity",
    "gravity_batch",
    "inverse_mass_matrix",
    "irb140",
    "kernels_of",
    "link_frames",
    "link_jacobian",
    "link_pose",
    "load_model",
    "mass_matrix",
    "mass_matrix_batch",
    "max_payload_at",
    "read_parameter_file",
    "prepare",
    "rnea",
    "rnea_batch",
    "rnea_derivatives",
    "workspace_load",
]
