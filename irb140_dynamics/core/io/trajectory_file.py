"""JointTrajectory files: a trajectory_msgs/JointTrajectory as the YAML ``ros2 topic pub`` takes."""

from __future__ import annotations

from collections.abc import Iterable

from irb140_dynamics.core.io.stamps import sec_nanosec
from irb140_dynamics.core.io.yaml_numbers import yaml_float, yaml_value


def joint_trajectory_text(joint_names, times, Q, QD, QDD, comments: Iterable[str] = ()) -> str:
    """A trajectory_msgs/JointTrajectory as the YAML ``ros2 topic pub`` takes (one point a line)."""
    lines = [f"# {line}".rstrip() for line in comments]
    lines.append(f"joint_names: {yaml_value(list(joint_names))}")
    lines.append("points:")
    for t, q, qd, qdd in zip(times, Q, QD, QDD):
        sec, nanosec = sec_nanosec(t)
        fields = [
            f"{name}: [{', '.join(yaml_float(v, 12) for v in values)}]"
            for name, values in (("positions", q), ("velocities", qd), ("accelerations", qdd))
        ]
        lines.append(f"- {{{', '.join(fields)}, time_from_start: {{sec: {sec}, nanosec: {nanosec}}}}}")
    return "\n".join(lines) + "\n"
