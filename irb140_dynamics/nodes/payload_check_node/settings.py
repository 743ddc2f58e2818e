"""payload_check_node's parameters, and the settings a check runs on: the limits and the
workspace analysis of the parameters in force (slow: built off the executor)."""

from __future__ import annotations

from dataclasses import dataclass

from irb140_dynamics.core import RigidBody, RobotModel
from irb140_dynamics.core.payload import (
    TorqueLimits,
    WorkspaceLoad,
    derive_torque_limits,
    workspace_load,
)
from irb140_dynamics.core.payload.stop import stopping
from irb140_dynamics.nodes.payload_check_node.payload_estimator import ESTIMATION_PARAMETERS
from irb140_dynamics.ros.parameters.specs import MAX_MASS, QOS_PARAMETERS, RELIABILITIES, Spec, check_choice

MIN_DIAGNOSTICS_PERIOD, MAX_DIAGNOSTICS_PERIOD = 0.1, 3600.0  # s
MAX_WARN_USE = 1e6  # %
MIN_ANALYSIS_TIME, MAX_ANALYSIS_TIME = 0.1, 3600.0  # s: check.analysis_timeout
MAX_WAIT = 600.0  # s: check.wait_timeout
NODE_PARAMETERS = [
    Spec(
        "rated_payload.mass",
        6.0,
        "the rated payload the torque limits are derived from",
        "kg",
        minimum=0.0,
        maximum=MAX_MASS,
    ),
    Spec("rated_payload.com", [0.0, 0.0, 0.0], "its centre of mass, in the flange frame", "m"),
    Spec(
        "diagnostics.warn_use",
        90.0,
        "a joint using more of its limit than this is a WARN",
        "%",
        minimum=0.0,
        maximum=MAX_WARN_USE,
    ),
    Spec(
        "diagnostics.period",
        1.0,
        f"check and publish /diagnostics this often, {MIN_DIAGNOSTICS_PERIOD:g} to {MAX_DIAGNOSTICS_PERIOD:g}; "
        "0 = only on ~/check",
        "s",
        minimum=0.0,
        maximum=MAX_DIAGNOSTICS_PERIOD,
        read_only=True,
    ),
    Spec(
        "check.analysis_timeout",
        20.0,
        f"the analysis of new parameters (limits, workspace) stops after this long, {MIN_ANALYSIS_TIME:g} to "
        f"{MAX_ANALYSIS_TIME:g}; what it has not proven by then ~/check answers UNPROVEN",
        "s",
        minimum=MIN_ANALYSIS_TIME,
        maximum=MAX_ANALYSIS_TIME,
        read_only=True,
    ),
    Spec(
        "check.wait_timeout",
        30.0,
        f"~/check waits this long for the analysis of new parameters in progress, 0 to {MAX_WAIT:g}; "
        "after it answers UNPROVEN (still running)",
        "s",
        minimum=0.0,
        maximum=MAX_WAIT,
    ),
    *ESTIMATION_PARAMETERS,
    *QOS_PARAMETERS,
]


@dataclass(frozen=True)
class Draft:
    """The validated parameters a check depends on, before the analysis."""

    model: RobotModel  # with the payload under test
    rated_payload: RigidBody
    warn_use: float
    rest_velocity: float  # rad/s, payload estimation
    rest_time: float  # s
    analysis_timeout: float = MAX_ANALYSIS_TIME  # s


@dataclass(frozen=True)
class PayloadCheckSettings:
    """What a check needs that depends only on the parameters, the workspace sweep included."""

    model: RobotModel  # with the payload under test
    rated_payload: RigidBody
    warn_use: float
    limits: TorqueLimits
    workspace: WorkspaceLoad  # the payload's worst static loads and largest mass
    rest_velocity: float  # rad/s, payload estimation
    rest_time: float  # s


def check_settings(values: dict) -> Draft:
    """Validate what the descriptors cannot (before a change is accepted)."""
    model = RobotModel.from_params(values)
    rated = RigidBody.validated("rated_payload", values["rated_payload.mass"], values["rated_payload.com"])
    period = values["diagnostics.period"]
    if period != 0.0 and not MIN_DIAGNOSTICS_PERIOD <= period <= MAX_DIAGNOSTICS_PERIOD:
        raise ValueError(
            f"diagnostics.period: must be 0 (only on ~/check) or between {MIN_DIAGNOSTICS_PERIOD:g} "
            f"and {MAX_DIAGNOSTICS_PERIOD:g} s, got {period}"
        )
    check_choice("qos.reliability", values["qos.reliability"], RELIABILITIES)
    return Draft(
        model,
        rated,
        values["diagnostics.warn_use"],
        values["estimation.rest_velocity"],
        values["estimation.rest_time"],
        values["check.analysis_timeout"],
    )


def finish_settings(draft: Draft, previous: PayloadCheckSettings | None) -> PayloadCheckSettings:
    """Derive the limits and analyse the workspace (seconds for a large model: runs off the
    executor, within draft.analysis_timeout); what the previous settings computed for the
    same arm is reused."""
    model, rated = draft.model, draft.rated_payload
    with stopping(seconds=draft.analysis_timeout):
        limits = previous.limits if _same_arm(draft, previous) else derive_torque_limits(model, rated)
        if analysed(draft, previous):
            workspace = previous.workspace
        else:
            workspace = workspace_load(model, model.payload, limits)
    return PayloadCheckSettings(model, rated, draft.warn_use, limits, workspace, draft.rest_velocity, draft.rest_time)


def _same_arm(draft: Draft, previous: PayloadCheckSettings | None) -> bool:
    """The same torque limits as before: the same joints, gravity and rated payload."""
    return previous is not None and (previous.model.joints, previous.model.gravity, previous.rated_payload) == (
        draft.model.joints,
        draft.model.gravity,
        draft.rated_payload,
    )


def analysed(draft: Draft, previous: PayloadCheckSettings | None) -> bool:
    """Nothing to analyse: the previous settings had the same arm and payload."""
    return _same_arm(draft, previous) and previous.model.payload == draft.model.payload
