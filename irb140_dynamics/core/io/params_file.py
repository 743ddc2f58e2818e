"""ROS 2 parameter files (YAML), read and written: the flat parameters of a model and a node.

Reading merges the ``/**`` section with the node's own; writing gives every node (``/**``)
the parameters, doubles written as doubles (see ``yaml_numbers``).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from functools import lru_cache
from typing import Any

from irb140_dynamics.core.io.text_files import read_text_file
from irb140_dynamics.core.io.yaml_numbers import yaml_value
from irb140_dynamics.core.model.robot_model import RobotModel


def read_parameter_file(path, node_name: str | None = None) -> dict[str, Any]:
    """The flat parameters of a ROS 2 parameter file (``/**`` merged with ``node_name``).

    The file is checked before it is parsed (``text_files``); YAML anchors and aliases,
    which no parameter file needs, are refused (a few lines of them can stand for gigabytes).
    A ValueError of one line names the file and what is wrong."""
    import yaml

    text = read_text_file(path, "parameter file")
    try:
        document = yaml.load(text, Loader=_no_alias_loader()) or {}
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        raise ValueError(f"{path}: not valid YAML{where}: {getattr(error, 'problem', None) or error}") from None
    except RecursionError:
        raise ValueError(f"{path}: nested too deeply to be a parameter file") from None
    except ValueError as error:  # a value YAML cannot convert (an integer of more than 4300 digits)
        raise ValueError(f"{path}: not a parameter file: {error}") from None
    if not isinstance(document, Mapping):
        raise ValueError(f"{path}: not a parameter file (expected a mapping of node names)")
    params: dict[str, Any] = {}
    for key in ("/**", node_name, f"/{node_name}" if node_name else None):
        if key and key in document:
            section = document[key]
            if not isinstance(section, Mapping) or not isinstance(section.get("ros__parameters", {}), Mapping):
                raise ValueError(f"{path}: {key}: expected 'ros__parameters:' and a mapping of parameters")
            _flatten(section.get("ros__parameters", {}), params)
    return params


def _flatten(tree: Mapping[str, Any], out: dict[str, Any]) -> None:
    """Nested groups as dotted names, without recursion."""
    pending = [("", tree)]
    while pending:
        prefix, node = pending.pop()
        for key, value in node.items():
            name = f"{prefix}{key}"
            if isinstance(value, Mapping):
                pending.append((f"{name}.", value))
            else:
                out[name] = value


@lru_cache(maxsize=1)
def _no_alias_loader():
    import yaml

    class NoAliasLoader(yaml.SafeLoader):
        def compose_node(self, parent, index):
            if self.check_event(yaml.AliasEvent):
                event = self.peek_event()
                raise yaml.composer.ComposerError(None, None, "YAML aliases are not accepted", event.start_mark)
            return super().compose_node(parent, index)

    return NoAliasLoader


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


_RCL_PARAMS_FILE_ERROR = re.compile(
    r"params file: '--params-file (?P<path>.+?)'\. Error: (?P<reason>.+?)"
    r"(?:(?: at line_num| near line|\. Error at line) (?P<line>\d+))?\s*(?:, at /|$)"
)


def rcl_refusal(text: str) -> str:
    """rcl's refusal of a command line (the text of its error) in one line; for a params
    file, ``path:line: reason in `the line```, with a hint for its commonest mistake."""
    found = _RCL_PARAMS_FILE_ERROR.search(text)
    if not found:
        return text.split(", at /")[0]
    path, reason, line = found["path"], found["reason"].rstrip(". "), found["line"]
    if line is None or int(line) < 1:  # rcl gives line 0 for some errors (a binary file)
        return f"{path}: {reason}"
    try:  # the line as it is, undecodable bytes (a binary file) escaped
        with open(path, encoding="utf-8", errors="backslashreplace") as stream:
            source = stream.read().splitlines()[int(line) - 1].strip()
    except (OSError, IndexError):
        source = "?"
    hint = "; write every number of a list as a double, e.g. 0.0 not 0" if "same type" in reason else ""
    return f"{path}:{line}: {reason} in `{source}`{hint}"
