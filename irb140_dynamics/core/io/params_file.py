"""ROS 2 parameter files (YAML), read and written: the flat parameters of a model and a node.

Reading merges the ``/**`` section with the node's own; writing gives every node (``/**``)
the parameters, doubles written as doubles (see ``yaml_numbers``).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from irb140_dynamics.core.io.yaml_numbers import yaml_value
from irb140_dynamics.core.model.robot_model import RobotModel


def read_parameter_file(path, node_name: str | None = None) -> dict[str, Any]:
    """The flat parameters of a ROS 2 parameter file (``/**`` merged with ``node_name``)."""
    import yaml

    with open(path) as stream:
        document = yaml.safe_load(stream) or {}
    params: dict[str, Any] = {}
    for key in ("/**", node_name, f"/{node_name}" if node_name else None):
        if key and key in document:
            _flatten(document[key].get("ros__parameters", {}), "", params)
    return params


def _flatten(tree: Mapping[str, Any], prefix: str, out: dict[str, Any]) -> None:
    for key, value in tree.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            _flatten(value, f"{name}.", out)
        else:
            out[name] = value


def load_model(path, node_name: str | None = None) -> RobotModel:
    """The model described by a ROS 2 parameter file."""
    return RobotModel.from_params(read_parameter_file(path, node_name))


def nested(flat: Mapping[str, Any]) -> dict:
    """Flat dotted parameter names as the nested groups of a parameter file."""
    tree: dict = {}
    for name, value in flat.items():
        *groups, leaf = name.split(".")
        node = tree
        for group in groups:
            node = node.setdefault(group, {})
        node[leaf] = value
    return tree


def parameter_file_text(params: Mapping[str, Any], comments: Iterable[str] = ()) -> str:
    """A ROS 2 parameter file giving ``params`` (flat names) to every node (``/**``).

    Doubles stay doubles (see the module's docstring): give floats for double parameters.
    """
    lines = [f"# {line}".rstrip() for line in comments]
    lines += ["/**:", "  ros__parameters:"]

    def emit(tree: Mapping[str, Any], indent: int):
        for key, value in tree.items():
            if isinstance(value, Mapping):
                lines.append(f"{' ' * indent}{key}:")
                emit(value, indent + 2)
            else:
                lines.append(f"{' ' * indent}{key}: {yaml_value(value)}")

    emit(nested(params), 4)
    return "\n".join(lines) + "\n"
