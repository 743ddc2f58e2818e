"""The names of the parameters the package's nodes declare besides the model's, for the
warning about unknown parameters (``overrides``): a parameter of a sibling node (one ``/**``
section of a params file serves them all) is not unknown. Kept here, below the nodes, so that
no lower floor loads a node; a test checks it against what each node declares.
"""

NODE_PARAMETER_NAMES = frozenset(
    {
        "acceleration.cutoff_frequency",
        "acceleration.mode",
        "check.analysis_timeout",
        "check.wait_timeout",
        "collision.observer_gain",
        "command_timeout",
        "diagnostics.period",
        "diagnostics.warn_use",
        "duration",
        "effort_commands.enabled",
        "effort_commands.source",
        "estimation.apply",
        "estimation.rest_time",
        "estimation.rest_velocity",
        "external_wrench.frame",
        "initial_positions",
        "integrator",
        "lockstep",
        "lockstep_timeout",
        "markers.rate",
        "model_label",
        "noise.effort",
        "noise.position",
        "period",
        "plot_file",
        "qos.depth",
        "qos.reliability",
        "rate",
        "rated_payload.com",
        "rated_payload.mass",
        "reference_timeout",
        "reset_hold",
        "retime.grid",
        "substeps",
        "thread_priority",
        "watch_topic",
    }
)
# per-joint parameters of a node: <joint><suffix>
PER_JOINT_SUFFIXES = (".collision_threshold", ".kd", ".kp")


def sibling_parameter_names(joint_names) -> set[str]:
    """The parameters of the package's nodes, the per-joint ones for these joints."""
    return set(NODE_PARAMETER_NAMES) | {
        f"{joint}{suffix}" for joint in joint_names or () for suffix in PER_JOINT_SUFFIXES
    }
