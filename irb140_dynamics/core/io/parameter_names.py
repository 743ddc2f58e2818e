"""The parameter names the package knows, and each name given that none of them is, with the
nearest known one.

Known: the model's parameters for its joints (``model_parameter_names``) and what any
executable of the package declares (``NODE_PARAMETER_NAMES``, per joint
``PER_JOINT_SUFFIXES``): one ``/**`` section of a params file serves every node and tool,
so a sibling's parameter is not unknown. A parameter of a joint the model does not have
(``joint_7.torque_limit`` on six joints) is unknown. A name under a parameter
(``joint_1.dh.a``: rcl flattens a mapping so, where ``dh`` is a list) is told as such.
Nodes warn about the unknown names (``ros.parameters.overrides``); tools refuse them
(``tools.common``). A test checks the catalog against what each node declares.
No ROS.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from irb140_dynamics.core.model.joints import param_prefix
from irb140_dynamics.core.model.robot_model import JOINT_DRIVE_FIELDS, JOINT_FIELDS

# the parameters the package's nodes declare besides the model's
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
        "external_wrench.links",
        "ft_contact_wrench.frame",
        "ft_sensor.apply_load",
        "ft_sensor.link",
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
PER_JOINT_FIELDS = frozenset(JOINT_FIELDS) | {suffix[1:] for suffix in PER_JOINT_SUFFIXES}  # <joint>.<field>
# the model's parameters that are not per joint, and where it comes from
MODEL_PARAMETER_NAMES = (
    "joint_names",
    "gravity",
    "friction.smoothing_velocity",
    "flange",
    "payload.mass",
    "payload.com",
    "payload.inertia",
    "model.name",
    "model.source",
    "robot_description",
    "model.urdf_file",
    "model.base_link",
    "model.tip_link",
    "model.held_positions",  # the joints a URDF's model leaves out, 'JOINT=VALUE' (core.io.arm_source)
    "payload.link",  # the URDF link the payload hangs on (core.io.arm_source)
    "tree.joints",  # a tree's or a model with mimic joints (see model.robot_model)
    "tree.parents",
    "flange_joint",
)
MIMIC_FIELDS = ("mimic.joint", "mimic.multiplier", "mimic.offset")  # <joint>.<field> of a mimic joint


def sibling_parameter_names(joint_names) -> set[str]:
    """The parameters of the package's nodes, the per-joint ones for these joints (named by
    the joint's name, as the nodes declare them, and by its parameter prefix)."""
    prefixes = {name for joint in joint_names or () for name in (joint, param_prefix(joint))}
    return set(NODE_PARAMETER_NAMES) | {f"{prefix}{suffix}" for prefix in prefixes for suffix in PER_JOINT_SUFFIXES}


def model_parameter_names(joint_names, from_urdf: bool = False) -> set[str]:
    """The model's parameters for these joints (every joint of ``model.joints``, mimic joints
    too); of a URDF's joints, only those its model takes from the parameters (limits,
    friction, armature: ``core.io.arm_source``)."""
    fields = JOINT_DRIVE_FIELDS if from_urdf else (*JOINT_FIELDS, *MIMIC_FIELDS)
    return set(MODEL_PARAMETER_NAMES) | {f"{param_prefix(joint)}.{field}" for joint in joint_names for field in fields}


def known_parameter_names(joint_names, from_urdf: bool = False) -> set[str]:
    """Every name a params file or ``-p`` may give for an arm of these joints."""
    return model_parameter_names(joint_names, from_urdf) | sibling_parameter_names(joint_names)


@dataclass(frozen=True)
class UnknownName:
    """A name given that is no known parameter: the nearest known name, or the known
    parameter it lies under (a list written as a mapping); ``joint``: the joint it names
    when the arm has no such joint (``joint_7`` of ``joint_7.torque_limit``)."""

    name: str
    nearest: str | None = None
    parent: str | None = None
    joint: str | None = None

    def why(self) -> str:
        """'did you mean joint_6.torque_limit?', 'joint_1.dh is one parameter, not a mapping', ..."""
        if self.parent is not None:
            return f"{self.parent} is one parameter, not a mapping"
        nearest = f"did you mean {self.nearest}?" if self.nearest else "no known name is near it"
        return f"the arm has no joint {self.joint}; {nearest}" if self.joint else nearest


def unknown_names(given: Iterable[str], known: Iterable[str], joint_names=None) -> list[UnknownName]:
    """The names of ``given`` not in ``known``, sorted, each with its nearest known name;
    ``joint_names``: the arm's (a per-joint name of another joint is told so)."""
    known = set(known)
    ordered = sorted(known)
    joints = {name for joint in joint_names or () for name in (joint, param_prefix(joint))}
    unknown = []
    for name in sorted(set(given) - known):
        parent = _known_parent(name, known)
        if parent is not None:
            unknown.append(UnknownName(name, parent=parent))
            continue
        nearest = difflib.get_close_matches(name, ordered, n=1, cutoff=0.6)
        joint, _, field = name.partition(".")
        other_joint = joint_names is not None and joint not in joints and field in PER_JOINT_FIELDS
        unknown.append(UnknownName(name, nearest[0] if nearest else None, joint=joint if other_joint else None))
    return unknown


def unknown_lines(unknown: list[UnknownName], ignored: str = "", describe: Callable[[str], str] | None = None):
    """One line per unknown name (one per parent for names under a parameter): 'unknown
    parameter NAME{ignored}; did you mean NEAREST?'; ``describe(parent)``: what that
    parameter is."""
    lines, by_parent = [], {}
    for entry in unknown:
        if entry.parent is not None:
            by_parent.setdefault(entry.parent, []).append(entry.name)
        elif entry.joint is not None:
            lines.append(f"unknown parameter {entry.name}{ignored}: {entry.why()}")
        else:
            hint = f"; did you mean {entry.nearest}?" if entry.nearest else ""
            lines.append(f"unknown parameter {entry.name}{ignored}{hint}")
    for parent, names in by_parent.items():
        what = describe(parent) if describe is not None else ""
        lines.append(
            f"unknown parameter{'s' if len(names) > 1 else ''} {', '.join(names)}{ignored}: "
            f"{parent} is one parameter, not a mapping{': ' + what if what else ''}"
        )
    return lines


def nearest_hint(name: str, known) -> str:
    """'; did you mean <the nearest known name>?', or '' when none is near."""
    nearest = difflib.get_close_matches(name, sorted(known), n=1, cutoff=0.6)
    return f"; did you mean {nearest[0]}?" if nearest else ""


def _known_parent(name: str, known: set[str]) -> str | None:
    """The known parameter ``name`` lies under (``joint_1.dh`` for ``joint_1.dh.a``), if any."""
    parent = name
    while "." in parent:
        parent = parent.rsplit(".", 1)[0]
        if parent in known:
            return parent
    return None
