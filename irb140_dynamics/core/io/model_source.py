"""The model a tool runs on, from files: a parameter file, a URDF, parameter overrides.

One place turns what a user gives a tool into a RobotModel, the way the nodes read theirs
(``ros/parameters/arm.py``):

- a parameter file whose ``model.source`` is ``parameters`` (the default): its joints
  (DH rows or URDF-form ``origin``/``axis``), merged over a defaults file (the tools give
  the package's config/irb140.yaml) the way the nodes declare defaults (per-joint values
  only for the default's own joints);
- a parameter file with ``model.source: robot_description``: the chain of the URDF in
  ``robot_description`` (text) or ``model.urdf_file`` (a path, relative to the working
  directory or else to the parameter file's folder) from ``model.base_link`` to
  ``model.tip_link``;
- a URDF file given directly (``urdf_file``, with ``base_link``/``tip_link``): the same,
  the parameter file (if any) giving the rest.

A URDF's model takes from the parameters what URDF has no (or no sure) place for, only
when given (the file or an override), never from the defaults: ``gravity``,
``friction.smoothing_velocity``, ``payload.*``, and for the chain's own joints
``<joint>.position_limits``, ``torque_limit``, ``velocity_limit``, ``acceleration_limit``,
``friction.viscous``, ``friction.coulomb`` and ``armature`` (URDF has no acceleration
limit nor armature; vendors' damping and friction are often placeholders). Overrides (``-p name:=value``, the value as YAML)
apply last. Errors are ValueErrors in one line naming the file or the parameter.
No ROS.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from irb140_dynamics.core.io.params_file import read_parameter_file
from irb140_dynamics.core.io.urdf import LoadedUrdf, UrdfError, load_urdf, read_urdf
from irb140_dynamics.core.model.robot_model import JOINT_DRIVE_FIELDS, RobotModel

SOURCES = ("parameters", "robot_description")
DESCRIPTION_PARAMETERS = ("gravity", "friction.smoothing_velocity")  # and payload.*: what a URDF's model takes
JOINT_PARAMETERS = JOINT_DRIVE_FIELDS  # and of each of its joints


@dataclass(frozen=True, eq=False)
class ToolModel:
    """A model and where it came from."""

    model: RobotModel
    origin: str  # for messages: 'params.yaml', 'arm.urdf (base -> tip)'
    urdf: LoadedUrdf | None = None  # the URDF's chain, when the model is a URDF's
    urdf_text: str | None = None
    parameters: Mapping[str, Any] | None = None  # the parameters read (the defaults' only for their own arm)


def description_values(values: Mapping[str, Any], joint_names=()) -> dict[str, Any]:
    """Of the parameters, those a URDF's model of these joints takes (see the module's docstring)."""
    own = {f"{name}.{field}" for name in joint_names for field in JOINT_PARAMETERS}
    return {k: v for k, v in values.items() if k in DESCRIPTION_PARAMETERS or k in own or k.startswith("payload.")}


def urdf_model(loaded: LoadedUrdf, values: Mapping[str, Any]) -> RobotModel:
    """The URDF chain's model with the parameters of ``values`` it takes applied."""
    given = description_values(values, loaded.model.joint_names)
    if not given:
        return loaded.model
    return RobotModel.from_params({**loaded.model.to_params(), **given})


def read_urdf_file(path, what: str = "URDF") -> str:
    """The text of a URDF file (``urdf.read_urdf``: bounded, a regular file, UTF-8), or
    ValueError in one line starting with ``what``."""
    try:
        return read_urdf(path)
    except UrdfError as error:
        raise ValueError(f"{what}: {error.reason}") from None


def parse_override(text: str) -> tuple[str, Any]:
    """``name:=value`` (value as YAML, as ``ros2 run ... -p`` reads it) -> (name, value)."""
    import yaml

    name, separator, value = text.partition(":=")
    if not separator or not name.strip():
        raise ValueError(f"-p {text}: expected NAME:=VALUE")
    try:
        return name.strip(), yaml.safe_load(value)
    except yaml.YAMLError as error:
        raise ValueError(f"-p {text}: the value is not YAML ({str(error).splitlines()[0]})") from None


def tool_model(
    params_file=None,
    urdf_file=None,
    base_link: str | None = None,
    tip_link: str | None = None,
    overrides: Mapping[str, Any] | None = None,
    defaults_file=None,
) -> ToolModel:
    """The model of the module's docstring; ``defaults_file``: the parameter file a
    params-form model starts from (the tools give the package's config/irb140.yaml), the
    model itself when there is no ``params_file``."""
    values = _parameters(params_file)
    values.update(overrides or {})
    source = values.get("model.source", "parameters")
    if source not in SOURCES:
        raise ValueError(f"model.source: must be one of {', '.join(SOURCES)}, got {source!r}")
    if urdf_file is not None or source == "robot_description":
        return _from_urdf(values, params_file, urdf_file, base_link, tip_link)
    if base_link or tip_link:
        raise ValueError(
            "--base and --tip choose a URDF's chain: give --urdf, or a parameter file with "
            "model.source: robot_description"
        )
    defaults = _parameters(defaults_file)
    if list(values.get("joint_names", defaults.get("joint_names", []))) != list(defaults.get("joint_names", [])):
        defaults = description_values(defaults)  # other joints: every per-joint value must be given
    origin = str(params_file or defaults_file or "parameters")
    try:
        merged = {**defaults, **values}
        return ToolModel(RobotModel.from_params(merged), origin, parameters=merged)
    except ValueError as error:  # it names the parameter; the file, when there is one
        raise ValueError(f"{params_file}: {error}" if params_file else str(error)) from None


def _from_urdf(values, params_file, urdf_file, base_link, tip_link) -> ToolModel:
    if urdf_file is not None:
        where, text = str(urdf_file), read_urdf_file(urdf_file)
    elif values.get("robot_description"):
        where, text = f"{params_file}: robot_description", str(values["robot_description"])
    elif values.get("model.urdf_file"):
        path = _beside(values["model.urdf_file"], params_file)
        where, text = str(path), read_urdf_file(path, "model.urdf_file")
    else:
        raise ValueError(
            f"{params_file or 'parameters'}: model.source is robot_description but neither "
            "robot_description nor model.urdf_file is given (or give --urdf FILE)"
        )
    base = base_link or values.get("model.base_link") or None
    tip = tip_link or values.get("model.tip_link") or None
    try:
        loaded = load_urdf(text, base, tip)
        model = urdf_model(loaded, values)
    except ValueError as error:
        raise ValueError(f"{where}: {error}") from None
    return ToolModel(model, f"{where} ({loaded.base_link} -> {loaded.tip_link})", loaded, text, values)


def _parameters(path) -> dict[str, Any]:
    if path is None:
        return {}
    try:  # a ValueError naming the file and why when it is none (missing, a folder, a device, bad YAML)
        return read_parameter_file(path)
    except OSError as error:
        raise ValueError(f"{path}: cannot be read ({error.strerror or error})") from None


def _beside(path, params_file) -> Path:
    """``path`` as given when it exists (relative to the working directory), else next to the params file."""
    path = Path(str(path))
    if path.is_absolute() or path.exists() or params_file is None:
        return path
    beside = Path(params_file).parent / path
    return beside if beside.exists() else path
