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
        with open(path) as stream:  # (libyaml's loader where PyYAML has it: 5x faster on a long file)
            loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
            return next((d for d in yaml.load_all(stream, Loader=loader) if d is not None), None)
    except OSError as error:
        raise ValueError(f"{path}: cannot read: {error.strerror}") from None
    except yaml.YAMLError as error:
        raise ValueError(f"{path}: not YAML: {str(error).splitlines()[0]}") from None


def joint_trajectory_yaml(message: dict) -> str:
    """A JointTrajectory mapping (header, joint_names, points) as YAML ``ros2 topic pub`` and
    ``ros2 topic echo`` both read: a point's lists on one line each, numbers exact."""
    import yaml

    dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)  # (libyaml's emitter: the same text, faster)
    return yaml.dump(message, Dumper=dumper, sort_keys=False, default_flow_style=None, width=10**6)
