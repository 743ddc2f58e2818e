"""payload_check_node's own parameters, all checked whole (``check_settings``), and their
analysis (``finish_settings``: slow, built off the executor; see core.payload.analysis)."""

from __future__ import annotations

from dataclasses import dataclass, replace

from irb140_dynamics.core import RigidBody, RobotModel
from irb140_dynamics.core.payload.analysis import PayloadAnalysis, analyse
from irb140_dynamics.ros.parameters.specs import MAX_MASS, QOS_PARAMETERS, Spec

MIN_PERIOD, MAX_PERIOD = 0.1, 3600.0  # s: diagnostics.period
NODE_PARAMETERS = [
    Spec(
        "rated_payload.mass", 6.0, "the rated payload the limits are derived from", "kg", minimum=0.0, maximum=MAX_MASS
    ),
    Spec("rated_payload.com", [0.0, 0.0, 0.0], "its centre of mass, in the flange frame", "m"),
    Spec("diagnostics.warn_use", 90.0, "a joint using more of its limit is a WARN", "%", minimum=0.0, maximum=1e6),
    Spec(
        "diagnostics.period",
        1.0,
        f"check and publish /diagnostics this often, {MIN_PERIOD:g} to {MAX_PERIOD:g}; 0 = only on ~/check",
        "s",
        read_only=True,
        minimum=0.0,
        maximum=MAX_PERIOD,
    ),
    Spec(
        "check.analysis_timeout",
        20.0,
        "the analysis of new parameters (limits, workspace) stops after this long; what it has not proven "
        "by then ~/check answers UNPROVEN",
        "s",
        read_only=True,
        minimum=0.1,
        maximum=3600.0,
    ),
    Spec(
        "check.wait_timeout",
        30.0,
        "~/check waits this long for the analysis of new parameters; then it answers UNPROVEN (still running)",
        "s",
        minimum=0.0,
        maximum=600.0,
    ),
    Spec("estimation.rest_velocity", 0.02, "at rest: every joint slower than this", "rad/s", minimum=1e-6, maximum=1e3),
    Spec("estimation.rest_time", 0.5, "a rest this long is a sample, one per pose", "s", minimum=0.0, maximum=3600.0),
    Spec("estimation.apply", False, "on a successful ~/estimate_payload, set payload.mass and payload.com"),
    *QOS_PARAMETERS,
]


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
