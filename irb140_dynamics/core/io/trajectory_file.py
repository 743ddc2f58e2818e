"""JointTrajectory files: a trajectory_msgs/JointTrajectory as the YAML ``ros2 topic pub`` takes."""

from __future__ import annotations

from collections.abc import Iterable

from irb140_dynamics.core.io.stamps import sec_nanosec
from irb140_dynamics.core.io.yaml_numbers import yaml_float, yaml_value


def joint_trajectory_text(joint_names, times, Q, QD, QDD, comments: Iterable[str] = ()) -> str:
    """A trajectory_msgs/JointTrajectory as the YAML ``ros2 topic pub`` takes (one point a line)."""
    lines = [f"joint_names: {yaml_value(list(joint_names))}"]
    lines.append("points:")
    for t, q, qd, qdd in zip(times, Q, QD, QDD):
        sec, nanosec = sec_nanosec(t)
        fields = [
            f"{name}: [{', '.join(yaml_float(v, 12) for v in values)}]"
            for name, values in (("positions", q), ("velocities", qd), ("accelerations", qdd))
        ]
        lines.append(f"- {{{', '.join(fields)}, time_from_start: {{sec: {sec}, nanosec: {nanosec}}}}}")
    return commented(comments, "\n".join(lines) + "\n")


def commented(comments: Iterable[str], text: str) -> str:
    """``text`` under ``comments``, a YAML comment line each (changed without writing the
    points again)."""
    return "".join(f"# {line}".rstrip() + "\n" for line in comments) + text


def read_joint_trajectory(path) -> object:
    """The first YAML document of ``path``: a JointTrajectory as ``ros2 topic echo`` prints it
    (the mapping; its fields are checked where it is turned into arrays), or ValueError in
    one line naming the file."""
    import yaml

    try:
        with open(path) as stream:
            text = stream.read()
        loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # (libyaml's where PyYAML has it: 5x faster)
        written = _as_written(text, loader)
        if written is not None:
            return written
        return next((d for d in yaml.load_all(text, Loader=loader) if d is not None), None)
    except OSError as error:
        raise ValueError(f"{path}: cannot read: {error.strerror}") from None
    except yaml.YAMLError as error:
        raise ValueError(f"{path}: not YAML: {str(error).splitlines()[0]}") from None


_FLOAT = r"-?(?:0|[1-9][0-9]*)\.[0-9]+(?:e[-+][0-9]+)?"  # what yaml_float writes (YAML reads it as float())
_FLOATS = rf"\[((?:{_FLOAT}, )*{_FLOAT})\]"
_INT = "(0|[1-9][0-9]*)"  # (no leading zero: YAML 1.1 reads 010 as octal)
_POINT = (
    rf"- \{{positions: {_FLOATS}, velocities: {_FLOATS}, accelerations: {_FLOATS}, "
    rf"time_from_start: \{{sec: {_INT}, nanosec: {_INT}\}}\}}"
)


def _as_written(text: str, loader) -> dict | None:
    """``text`` read as YAML reads it when its points are exactly as joint_trajectory_text
    writes them (one a line, to the end of the file), without YAML's Python constructor
    (seconds for the 7,500 points of a 2 MB file); else None. Everything before the points
    is read by YAML."""
    import re

    import yaml

    head, found, body = text.partition("\npoints:\n")
    lines = body.split("\n")
    if lines[-1] == "":
        lines.pop()
    if not found or not lines or head.startswith("\ufeff"):
        return None
    point = re.compile(_POINT)
    points = []
    for line in lines:
        match = point.fullmatch(line)
        if match is None:
            return None
        q, qd, qdd, sec, nanosec = match.groups()
        points.append(
            {
                "positions": [float(x) for x in q.split(", ")],
                "velocities": [float(x) for x in qd.split(", ")],
                "accelerations": [float(x) for x in qdd.split(", ")],
                "time_from_start": {"sec": int(sec), "nanosec": int(nanosec)},
            }
        )
    try:
        documents = list(yaml.load_all(head + "\npoints: []\n", Loader=loader))
    except yaml.YAMLError:
        return None  # (the whole file read again says it)
    if len(documents) != 1 or not isinstance(documents[0], dict) or documents[0].get("points") != []:
        return None
    documents[0]["points"] = points
    return documents[0]


def joint_trajectory_yaml(message: dict) -> str:
    """A JointTrajectory mapping (header, joint_names, points) as YAML ``ros2 topic pub`` and
    ``ros2 topic echo`` both read: a point's lists on one line each, numbers exact."""
    import yaml

    dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)  # (libyaml's emitter: the same text, faster)
    return yaml.dump(message, Dumper=dumper, sort_keys=False, default_flow_style=None, width=10**6)
