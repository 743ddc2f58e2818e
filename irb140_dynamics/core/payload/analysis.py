"""What a payload check runs on: an arm's torque limits and its payload's worst static loads
over the workspace (``PayloadAnalysis``), reused where a new arm or payload leaves them as
they were.

Seconds for a large arm: a node builds it off its message thread, within a time budget;
what the budget leaves unproven, the check answers UNPROVEN (see ``stop``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from irb140_dynamics.core.model.rigid_body import RigidBody
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.payload.limits import TorqueLimits, WorkspaceLoad, derive_torque_limits, workspace_load
from irb140_dynamics.core.payload.stop import stopping


@dataclass(frozen=True)
class PayloadAnalysis:
    """The limits of ``model`` (given, or derived from ``rated_payload``) and the worst loads
    of its payload under them."""

    model: RobotModel  # with the payload under test
    rated_payload: RigidBody
    limits: TorqueLimits
    workspace: WorkspaceLoad

    def same_limits(self, model: RobotModel, rated_payload: RigidBody) -> bool:
        """The limits hold for ``model`` too: the same joints, gravity and rated payload."""
        return (self.model.joints, self.model.gravity, self.rated_payload) == (
            model.joints,
            model.gravity,
            rated_payload,
        )

    def covers(self, model: RobotModel, rated_payload: RigidBody) -> bool:
        """Nothing to analyse for ``model``: the same limits and payload."""
        return self.same_limits(model, rated_payload) and self.model.payload == model.payload


def analyse(
    model: RobotModel,
    rated_payload: RigidBody,
    previous: PayloadAnalysis | None = None,
    seconds: float = math.inf,
) -> PayloadAnalysis:
    """The analysis of ``model`` and its payload within ``seconds``, what ``previous`` holds
    for the same arm reused."""
    with stopping(seconds=seconds):
        if previous is not None and previous.same_limits(model, rated_payload):
            limits = previous.limits
        else:
            limits = derive_torque_limits(model, rated_payload)
        if previous is not None and previous.covers(model, rated_payload):
            workspace = previous.workspace
        else:
            workspace = workspace_load(model, model.payload, limits)
    return PayloadAnalysis(model, rated_payload, limits, workspace)
