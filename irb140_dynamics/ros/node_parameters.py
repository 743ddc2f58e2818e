"""The parameters of each node of the package besides the model's (see params.model_specs).

Listed together so that any node can tell a parameter of a sibling (given in a shared
``/**`` params file section) from a typo.
"""

from __future__ import annotations

from .params import QOS_PARAMETERS, Spec

ACCELERATION_MODES = ("zero", "differentiate")
EFFORT_SOURCES = ("feedforward", "gravity")
MAX_CUTOFF_FREQUENCY = 1e6  # Hz
MAX_DURATION = 1e6  # s, for timeouts
MIN_DIAGNOSTICS_PERIOD, MAX_DIAGNOSTICS_PERIOD = 0.1, 3600.0  # s
MAX_WARN_USE = 1e6  # %

ID_NODE = [
    Spec("acceleration.mode", "zero",
         "qdd when no ~/reference gives it: 'zero', or 'differentiate' the measured velocities (low-pass "
         "filtered; for monitoring: as a command it would feed the measured acceleration back, "
         "so effort_commands never use it)"),
    Spec("acceleration.cutoff_frequency", 20.0, "cut-off of the velocity differentiation filter", "Hz",
         minimum=1e-3, maximum=MAX_CUTOFF_FREQUENCY),
    Spec("reference_timeout", 0.5, "a ~/reference older than this (node clock) is no longer used; 0 = never",
         "s", minimum=0.0, maximum=MAX_DURATION),
    Spec("effort_commands.enabled", False, "also publish torques on effort_commands (Float64MultiArray)",
         read_only=True),
    Spec("effort_commands.source", "feedforward", "which torques go to effort_commands: 'feedforward' or 'gravity'"),
    *QOS_PARAMETERS,
]

PAYLOAD_CHECK_NODE = [
    Spec("rated_payload.mass", 6.0, "the rated payload the torque limits are derived from", "kg",
         minimum=0.0),
    Spec("rated_payload.com", [0.0, 0.0, 0.0], "its centre of mass, in the flange frame", "m"),
    Spec("diagnostics.warn_use", 90.0, "a joint using more of its limit than this is a WARN", "%",
         minimum=0.0, maximum=MAX_WARN_USE),
    Spec("diagnostics.period", 1.0,
         f"check and publish /diagnostics this often, {MIN_DIAGNOSTICS_PERIOD:g} to {MAX_DIAGNOSTICS_PERIOD:g}; "
         "0 = only on ~/check", "s", minimum=0.0, maximum=MAX_DIAGNOSTICS_PERIOD, read_only=True),
    *QOS_PARAMETERS,
]

DEMO_NODE = ["rate"]  # demo_node declares its own

PACKAGE_PARAMETERS = {spec.name for spec in ID_NODE + PAYLOAD_CHECK_NODE} | set(DEMO_NODE)
