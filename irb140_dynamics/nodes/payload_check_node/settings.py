"""payload_check_node's own parameters; the settings they give, checked whole and analysed,
are core.payload.analysis'."""

from __future__ import annotations

from irb140_dynamics.core.payload.analysis import MAX_PERIOD, MIN_PERIOD
from irb140_dynamics.ros.parameters.specs import MAX_MASS, QOS_PARAMETERS, Spec

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
