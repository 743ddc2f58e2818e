"""Just enough of the launch and launch_ros API to run a launch file's
generate_launch_description() without them (they are not on PyPI): the actions are kept
as written, and ``resolve`` evaluates their substitutions the way ros2 launch would with
the arguments' defaults (or values given)."""

from __future__ import annotations

import importlib.util
import sys
import types
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml


@dataclass
class LaunchDescription:
    entities: list


@dataclass
class DeclareLaunchArgument:
    name: str
    default_value: Any = None
    description: str = ""


@dataclass
class LaunchConfiguration:
    variable_name: str


@dataclass
class PathJoinSubstitution:
    substitutions: list


@dataclass
class FindPackageShare:
    package: str


@dataclass
class ParameterValue:
    value: Any
    value_type: Any = None


@dataclass
class IfCondition:
    predicate_expression: Any


@dataclass
class LogInfo:
    msg: Any
    condition: IfCondition | None = None


@dataclass
class Node:
    package: str = ""
    executable: str = ""
    name: str | None = None
    output: str = ""
    parameters: list = field(default_factory=list)
    arguments: list = field(default_factory=list)
    remappings: list = field(default_factory=list)
    condition: IfCondition | None = None


MODULES = {
    "launch": {"LaunchDescription": LaunchDescription},
    "launch.actions": {"DeclareLaunchArgument": DeclareLaunchArgument, "LogInfo": LogInfo},
    "launch.conditions": {"IfCondition": IfCondition},
    "launch.substitutions": {"LaunchConfiguration": LaunchConfiguration, "PathJoinSubstitution": PathJoinSubstitution},
    "launch_ros": {},
    "launch_ros.actions": {"Node": Node},
    "launch_ros.parameter_descriptions": {"ParameterValue": ParameterValue},
    "launch_ros.substitutions": {"FindPackageShare": FindPackageShare},
}


def load_description(path: Path, monkeypatch) -> LaunchDescription:
    """generate_launch_description() of a launch file, with this stub as launch and launch_ros."""
    for name, names in MODULES.items():
        module = types.ModuleType(name)
        module.__dict__.update(names)
        monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location(path.stem.replace(".", "_"), path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.generate_launch_description()


def resolve(value, arguments: dict[str, str], share: Path):
    """A substitution (or a list/dict of them) evaluated: LaunchConfiguration -> its
    argument, FindPackageShare -> ``share``; a ParameterValue typed as launch_ros types it,
    a substituted string in a parameter dict read as YAML (as launch_ros does)."""
    if isinstance(value, LaunchConfiguration):
        return arguments[value.variable_name]
    if isinstance(value, FindPackageShare):
        return str(share)
    if isinstance(value, PathJoinSubstitution):
        return str(Path(*(resolve(part, arguments, share) for part in value.substitutions)))
    if isinstance(value, ParameterValue):
        text = resolve(value.value, arguments, share)
        return value.value_type(text) if value.value_type is not None else yaml.safe_load(text)
    if isinstance(value, list):
        return [resolve(item, arguments, share) for item in value]
    if isinstance(value, dict):
        return {key: _typed(resolve(item, arguments, share), item) for key, item in value.items()}
    return value


def _typed(resolved, original):
    """launch_ros reads a substituted parameter value as YAML; a plain value stays as it is."""
    if isinstance(original, LaunchConfiguration) and isinstance(resolved, str):
        return yaml.safe_load(resolved)
    return resolved


def arguments_of(description: LaunchDescription, given: dict[str, str], share: Path) -> dict[str, str]:
    """The launch arguments: the given ones over the declared defaults (resolved)."""
    values = {}
    for entity in description.entities:
        if isinstance(entity, DeclareLaunchArgument):
            values[entity.name] = given.get(entity.name, resolve(entity.default_value, values, share))
    return values


def nodes_of(description: LaunchDescription, arguments: dict[str, str] | None = None, share: Path = Path("/")) -> list:
    """The nodes launched with ``arguments`` (None: the defaults): those without a condition
    or whose condition holds (as launch reads it: 'true' or '1', any case)."""
    arguments = arguments_of(description, {}, share) if arguments is None else arguments
    return [entity for entity in description.entities if isinstance(entity, Node) and holds(entity, arguments, share)]


def holds(entity, arguments: dict[str, str], share: Path) -> bool:
    if getattr(entity, "condition", None) is None:
        return True
    return str(resolve(entity.condition.predicate_expression, arguments, share)).strip().lower() in ("true", "1")
