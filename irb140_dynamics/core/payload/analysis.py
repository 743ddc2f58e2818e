"""What a payload check runs on: an arm's torque limits and its payload's worst static loads
over the workspace (``PayloadAnalysis``), reused where a new arm or payload leaves them as
they were.

Seconds for a large arm: a node builds it off its message thread, within a time budget;
what the budget leaves unproven, the check answers UNPROVEN (see ``stop``). ``Settings``:
what payload_check_node runs on, checked whole from its parameter values (``check_settings``)
and then analysed (``finish_settings``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from irb140_dynamics.core.model.rigid_body import RigidBody
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.core.payload.limits import TorqueLimits, WorkspaceLoad, derive_torque_limits, workspace_load
from irb140_dynamics.core.payload.stop import stopping

MIN_PERIOD, MAX_PERIOD = 0.1, 3600.0  # s: diagnostics.period


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


@dataclass(frozen=True)
class Settings:
    """The parameters a check and the payload estimate run on; ``analysis`` None until built."""

    model: RobotModel  # with the payload under test
    rated_payload: RigidBody
    warn_use: float  # %
    rest_velocity: float  # rad/s
    rest_time: float  # s
    analysis_timeout: float  # s
    analysis: PayloadAnalysis | None = None

    def same_analysis(self, previous: Settings | None) -> bool:
        """Nothing to analyse: ``previous`` had the same arm and payload."""
        return previous is not None and previous.analysis.covers(self.model, self.rated_payload)


def check_settings(values: dict) -> Settings:
    """The values checked whole, before a change is accepted (ValueError naming the parameter)."""
    model = RobotModel.from_params(values)
    rated = RigidBody.validated("rated_payload", values["rated_payload.mass"], values["rated_payload.com"])
    period = values["diagnostics.period"]
    if period != 0.0 and not MIN_PERIOD <= period <= MAX_PERIOD:
        raise ValueError(
            f"diagnostics.period: must be 0 (only on ~/check) or between {MIN_PERIOD:g} and {MAX_PERIOD:g} s, "
            f"got {period}"
        )
    rest = values["estimation.rest_velocity"], values["estimation.rest_time"]
    return Settings(model, rated, values["diagnostics.warn_use"], *rest, values["check.analysis_timeout"])


def finish_settings(draft: Settings, previous: Settings | None) -> Settings:
    """``draft`` analysed within its analysis_timeout, what ``previous`` analysed reused."""
    analysis = analyse(draft.model, draft.rated_payload, previous and previous.analysis, draft.analysis_timeout)
    return replace(draft, analysis=analysis)
