"""The arm a user gives, read one way for every node and every tool (``read_arm``).

What a user gives: parameter values (params files merged in order, then ``-p``, as flat
dotted names, as rcl gives them to a node: ``given_values``), over the default arm's values
(config/irb140.yaml), and maybe a URDF. The arm is:

- with ``model.source: parameters`` (the default) and no URDF: the model of the values
  merged over the defaults; the default's per-joint values only for the default's own
  joints (a params file naming other joints gives every value of them: nothing is silently
  borrowed); its name ``model.name`` (default ``irb140``);
- with a URDF (a tool's ``--urdf``; a node's text from the topic; or ``model.source:
  robot_description`` with the text in ``robot_description``, else the file
  ``model.urdf_file``, relative to the working directory or else to the params file's
  folder): the chain from ``model.base_link`` (or ``--base``; default: the root link) to
  ``model.tip_link`` (``--tip``; default: the only leaf), its name the URDF's ``<robot
  name>``. Its model takes from the values only what URDF has no (or no sure) place for,
  and only when given: ``gravity`` (in the URDF root link's frame, turned into base_link's
  as docs/urdf.md states; absent: 9.81 m/s^2 along the root's -z),
  ``friction.smoothing_velocity``, ``payload.*`` (in the tip link's frame), and for the
  chain's own joints ``position_limits``, ``torque_limit``, ``velocity_limit``,
  ``acceleration_limit``, ``friction.viscous``, ``friction.coulomb``, ``armature``.
  With no ``model.tip_link`` and several leaves, the whole tree below base_link (every
  independent joint; mimic joints follow theirs). ``payload.link`` names the URDF link the
  payload hangs on (``LoadedUrdf.with_flange_at``; ``payload.com``/``.inertia`` in its
  frame); empty: the chain's tip link. On a tree a payload (``payload.mass`` > 0) needs it.
  The joints the model leaves out (the rest of a tree when ``model.tip_link`` names one
  end effector; those above base_link) are held at ``model.held_positions`` (a list of
  'JOINT=VALUE', rad or m; a tool's ``--hold JOINT=VALUE`` over them), else at zero or the
  limit nearest it (``core.io.urdf.held``): ``held_chain``, which refuses a bad one naming
  the option (``HeldPositionError``); on an arm of parameters any is refused.

Names given that are no parameter of the package: ``core.io.parameter_names``.
Errors: a ValueError in one line naming the file or the parameter. No ROS.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from irb140_dynamics.core.errors import one_line
from irb140_dynamics.core.io.params_file import read_parameter_file
from irb140_dynamics.core.io.urdf import LoadedUrdf, UrdfError, load_urdf, read_urdf
from irb140_dynamics.core.io.urdf.held import HeldError
from irb140_dynamics.core.model.joints import param_prefix
from irb140_dynamics.core.model.rigid_body import finite_numbers
from irb140_dynamics.core.model.robot_model import JOINT_DRIVE_FIELDS, RobotModel

SOURCES = ("parameters", "robot_description")
# what an arm of parameters lacks for a URDF's names, in the nodes' words (the tools' "give --urdf, ..."
# in tools.common.in_option_words)
GIVE_A_URDF = "give model.source: robot_description with model.urdf_file"
DEFAULT_ROBOT_NAME = "irb140"  # model.name when none is given (the nodes' default too)
URDF_ROBOT_NAME = "robot"  # a URDF's name when its <robot> has none
ARM_PARAMETERS = ("gravity", "friction.smoothing_velocity", "payload.mass", "payload.com", "payload.inertia")
HELD = "model.held_positions"  # ['JOINT=VALUE', ...]: the joints the URDF's model leaves out (tools: --hold)
URDF_PARAMETERS = (  # model.source robot_description's (name, default, description); (): a string array, unset
    (
        "robot_description",
        "",
        "the URDF text (model.source robot_description); empty: model.urdf_file, else the robot_description topic",
    ),
    ("model.urdf_file", "", "a URDF file, when robot_description is empty; empty: the robot_description topic"),
    ("model.base_link", "", "the URDF link the chain starts from (fixed); empty: the root link"),
    (
        "model.tip_link",
        "",
        "the URDF link where the chain ends, the payload's frame; empty: the only leaf, or with several the whole tree",
    ),
    (
        HELD,
        (),
        "'JOINT=VALUE' (rad, m) of joints the model leaves out (the rest of the tree, those above model.base_link); "
        "not given: zero, or the limit nearest it; a mimic joint follows its joint",
    ),
)


class HeldPositionError(ValueError):
    """A held position refused (``held_chain``), in one line naming the option that gave it."""


@dataclass(frozen=True)
class UrdfText:
    """A URDF's text and where it came from (for messages: a path, 'robot_description topic')."""

    text: str
    origin: str


@dataclass(frozen=True, eq=False)
class Arm:
    """The arm read: its model, its name, where it came from, and its URDF chain when it is a URDF's."""

    model: RobotModel
    robot_name: str
    origin: str  # 'params.yaml', 'arm.urdf (base_link -> tool0)'
    urdf: LoadedUrdf | None = None  # base and tip link, held joints, warnings, notes
    urdf_text: str | None = None
    given: Mapping[str, Any] = field(default_factory=dict)  # the values it was read from (a tool's rated_payload.*)


def given_values(params_files: Iterable = (), overrides: Iterable[tuple[str, Any]] = ()) -> dict[str, Any]:
    """The values given: each params file's ``/**`` section merged in order, then the overrides."""
    values: dict[str, Any] = {}
    for path in params_files:
        try:  # a ValueError naming the file and why when it is none (missing, a folder, a device, bad YAML)
            values.update(read_parameter_file(path))
        except OSError as error:
            raise ValueError(f"{path}: cannot be read ({error.strerror or error})") from None
    values.update(overrides)
    return values


def read_urdf_file(path, what: str = "URDF") -> UrdfText:
    """A URDF file's text (``urdf.read_urdf``: bounded, a regular file, UTF-8), or a ValueError
    in one line starting with ``what``."""
    try:
        return UrdfText(read_urdf(path), str(path))
    except UrdfError as error:
        raise ValueError(f"{what}: {error.reason}") from None


def read_arm(
    values: Mapping[str, Any],
    defaults: Mapping[str, Any] | None = None,
    urdf: UrdfText | LoadedUrdf | None = None,
    base_link: str | None = None,
    tip_link: str | None = None,
    origin: str | None = None,
    relative_to: str | Path | None = None,
    hold: Iterable[str] = (),
) -> Arm:
    """The arm of the module's docstring.

    ``values``: the parameter values given (a node's: all it has); ``defaults``: the default
    arm's values; ``urdf``: a URDF given besides the values (text, or a chain read already:
    then ``base_link``/``tip_link`` are its own); ``base_link``/``tip_link``: the chain's ends
    over ``model.base_link``/``model.tip_link``; ``origin``: where the values came from (a
    params file), named in errors; ``relative_to``: the folder ``model.urdf_file`` may be
    relative to; ``hold``: a tool's --hold entries, 'JOINT=VALUE' over ``model.held_positions``.
    """
    source = values.get("model.source", "parameters")
    if source not in SOURCES:
        raise ValueError(f"model.source: must be one of {', '.join(SOURCES)}, got {source!r}")
    if urdf is None and source == "robot_description":
        urdf = _described_urdf(values, origin, relative_to)
    if urdf is not None:
        return _urdf_arm(values, urdf, base_link or values.get("model.base_link") or None,
                         tip_link or values.get("model.tip_link") or None, origin, hold)  # fmt: skip
    held = "--hold" if hold else HELD if values.get(HELD) else None
    if held:
        raise HeldPositionError(f"{held} holds joints of a URDF: {GIVE_A_URDF}")
    if values.get("payload.link"):
        raise ValueError(f"payload.link names a URDF link: {GIVE_A_URDF}")
    if base_link or tip_link:
        raise ValueError(
            "--base and --tip choose a URDF's chain: give --urdf, or a parameter file with "
            "model.source: robot_description"
        )
    defaults = dict(defaults or {})
    names = values.get("joint_names", defaults.get("joint_names", []))
    if list(names) != list(defaults.get("joint_names", [])):
        defaults = {name: value for name, value in defaults.items() if name in ARM_PARAMETERS}
    merged = {**defaults, **values}
    try:
        model = RobotModel.from_params(merged)
    except ValueError as error:  # it names the parameter; the file, when there is one
        raise ValueError(f"{origin}: {one_line(error)}" if origin else one_line(error)) from None
    return Arm(model, str(merged.get("model.name") or DEFAULT_ROBOT_NAME), origin or "parameters")


def urdf_values(values: Mapping[str, Any], loaded: LoadedUrdf) -> dict[str, Any]:
    """Of the values, those the URDF chain's model takes, gravity turned into base_link's frame."""
    own = {f"{param_prefix(name)}.{field}" for name in loaded.model.joint_names for field in JOINT_DRIVE_FIELDS}
    taken = {k: v for k, v in values.items() if k in ARM_PARAMETERS or k in own}
    if "gravity" in taken:
        taken["gravity"] = loaded.in_base(finite_numbers("gravity", taken["gravity"], 3))
    return taken


def payload_carrier(loaded: LoadedUrdf, values: Mapping[str, Any]) -> RobotModel:
    """The URDF's model with its flange at ``payload.link`` (empty: as read, the chain's tip);
    ValueError naming payload.link for a link the model does not move, or for a payload
    (``payload.mass`` > 0) on a tree with no link named."""
    link = values.get("payload.link") or ""
    if not isinstance(link, str):
        raise ValueError(f"payload.link: must be a URDF link's name, got {link!r}")
    if link:
        try:
            return loaded.with_flange_at(link)
        except UrdfError as error:
            raise ValueError(f"payload.link: {error.reason}") from None
    mass = values.get("payload.mass") or 0.0
    if not is_one_chain(loaded.model) and isinstance(mass, (int, float)) and mass > 0.0:
        raise ValueError(
            f"payload.link: the model is a tree ({loaded.model.n} joints below {loaded.base_link!r}); "
            "name the URDF link the payload hangs on"
        )
    return loaded.model


def is_one_chain(model: RobotModel) -> bool:
    """Every independent joint is on the path from the base to the flange's link (mimic joints
    may hang off it: a gripper's other finger following the chain's): one tip, the payload's default place."""
    path, k = set(), model.carrier
    while k >= 0:
        path.add(k)
        k = model.parent[k]
    return path.issuperset(model.independent)


def model_summary(loaded: LoadedUrdf) -> str:
    """A URDF's model in one line, as the nodes log it: 'base -> tool0, 6 joints [...]; held at zero: a, b'."""
    names = list(loaded.model.joint_names)
    return "; ".join(filter(None, (f"{urdf_span(loaded)}, {len(names)} joints {names}", loaded.held_summary())))


def urdf_span(loaded: LoadedUrdf) -> str:
    """What of the URDF the model is, for messages: 'base_link -> tool0', or 'the tree below base'."""
    if is_one_chain(loaded.model):
        return f"{loaded.base_link} -> {loaded.tip_link}"
    return f"the tree below {loaded.base_link}"


def held_chain(text: str, base_link=None, tip_link=None, held=None, hold: Iterable[str] = ()) -> LoadedUrdf:
    """``load_urdf`` with the held positions given: ``held`` (``model.held_positions``'s
    value: 'JOINT=VALUE' entries, or None), ``hold`` (a tool's --hold entries) over them;
    HeldPositionError in one line naming the option and the entry for a bad one."""
    given = {**_held_entries(held, HELD), **_held_entries(hold, "--hold")}
    try:
        return load_urdf(text, base_link, tip_link, held={name: value for name, (value, _) in given.items()})
    except HeldError as error:
        value, option = given[error.joint]
        raise HeldPositionError(f"{option} {error.joint}={value:g}: {error.reason}") from None


def _held_entries(entries, option: str) -> dict[str, tuple[float, str]]:
    """'JOINT=VALUE' entries -> {joint: (value, option)}; HeldPositionError naming ``option``
    for one that is no such text, a value that is no finite number, a joint given twice."""
    if entries is None or (isinstance(entries, (list, tuple)) and not entries):
        return {}
    if isinstance(entries, str) or not isinstance(entries, (list, tuple)):
        raise HeldPositionError(f"{option}: expected a list of 'JOINT=VALUE' texts, got {entries!r}")
    found: dict[str, tuple[float, str]] = {}
    for entry in entries:
        name, _, text = str(entry).rpartition("=")
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (isinstance(entry, str) and name.strip() and math.isfinite(value)):
            raise HeldPositionError(f"{option} {entry}: expected JOINT=VALUE, the value a finite number (rad, m)")
        if name.strip() in found:
            raise HeldPositionError(f"{option} {entry}: {name.strip()} is given twice")
        found[name.strip()] = (value, option)
    return found


def _urdf_arm(values, urdf, base_link, tip_link, origin, hold=()) -> Arm:
    """A chain read already (a node's) names no file in its errors: the parameter is named."""
    text, where = None, origin or "robot_description"
    if isinstance(urdf, UrdfText):
        text, where = urdf.text, urdf.origin
        try:
            loaded = held_chain(urdf.text, base_link, tip_link, values.get(HELD), hold)
        except HeldPositionError:
            raise
        except ValueError as error:
            raise ValueError(f"{where}: {one_line(error)}") from None
    else:
        loaded = urdf
    try:
        carrying = payload_carrier(loaded, values)
        taken = urdf_values(values, loaded)
        model = RobotModel.from_params({**carrying.to_params(), **taken}) if taken else carrying
    except ValueError as error:
        named = origin or (text is not None and where)
        raise ValueError(f"{named}: {one_line(error)}" if named else one_line(error)) from None
    name = loaded.robot_name or URDF_ROBOT_NAME
    return Arm(model, name, f"{where} ({urdf_span(loaded)})", loaded, text)


def _described_urdf(values, origin, relative_to) -> UrdfText:
    """The URDF of ``model.source: robot_description``: ``robot_description``, else ``model.urdf_file``."""
    if values.get("robot_description"):
        return UrdfText(str(values["robot_description"]), f"{origin or 'parameters'}: robot_description")
    if values.get("model.urdf_file"):
        return read_urdf_file(_beside(values["model.urdf_file"], relative_to), "model.urdf_file")
    raise ValueError(
        f"{origin or 'parameters'}: model.source is robot_description but neither "
        "robot_description nor model.urdf_file is given (or give --urdf FILE)"
    )


def _beside(path, folder) -> Path:
    """``path`` as given when it exists (relative to the working directory), else in ``folder``."""
    path = Path(str(path))
    if path.is_absolute() or path.exists() or folder is None:
        return path
    beside = Path(folder) / path
    return beside if beside.exists() else path
