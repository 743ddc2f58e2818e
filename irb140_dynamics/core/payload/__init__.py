"""The payload room: what the arm can carry, and what it carries now.

- ``limits``: joint torque limits (given, or derived from the rated payload), the largest
  payload at a pose and the worst static load over the workspace;
- ``check``: a payload against those limits, now and in its proven worst pose;
- ``family``: a payload's torques as affine in its mass, and their proven extremes;
- ``workspace``: the joint ranges and the sampled search for the worst pose;
- ``path``: a payload on a link of a tree: the joints it loads, and the rest of the tree's
  proven share of their static torques;
- ``analysis``: what a check runs on (the limits and the workspace's worst loads), reused
  where a new arm or payload leaves them as they were;
- ``mass_com_estimation``: the payload's mass and centre of mass from efforts at rest;
- ``rest_samples``: the rests of a stream of joint states, and the estimate they give;
- ``stop``: when a long analysis stops early (cancelled, or out of time);
- ``proof/``: the rigorous bounds (harmonic sums, interval boxes, branch and bound).

May import: ``core.model``, ``core.scalars``, ``core.algorithms``, ``core.codegen``, the
verbs in ``core.dynamics`` and ``core.kinematics``. Nothing of ROS.
"""

from irb140_dynamics.core.payload.check import PayloadCheck, check_payload
from irb140_dynamics.core.payload.limits import (
    RATED_PAYLOAD,
    RTOL,
    MaxPayload,
    TorqueLimits,
    WorkspaceLoad,
    derive_torque_limits,
    loads,
    max_payload_at,
    payload_family,
    workspace_load,
)

__all__ = [
    "RATED_PAYLOAD",
    "RTOL",
    "MaxPayload",
    "PayloadCheck",
    "TorqueLimits",
    "WorkspaceLoad",
    "check_payload",
    "derive_torque_limits",
    "loads",
    "max_payload_at",
    "payload_family",
    "workspace_load",
]
