"""retime: check a JointTrajectory against the arm's limits, or re-time it time-optimally.

    retime [--params-file F] [--urdf U [--base L] [--tip L]] [-p NAME:=VALUE] [--payload-mass M] IN.yaml OUT.yaml
           [--plot P.png]
    retime --check-only [--params-file F] [--urdf U ...] [-p NAME:=VALUE] [--payload-mass M] IN.yaml [--plot P.png]

IN.yaml: a trajectory_msgs/JointTrajectory as ``ros2 topic echo --once`` prints it (header,
joint_names, points with positions, velocities, accelerations, effort, time_from_start
{sec, nanosec}); joints in any order, matched to the model's by name. The model, read as
every tool and node reads it (``core.io.arm_source``): the package's IRB-140, the params
file's ``/**`` section over it, then -p; or the URDF's chain with the params file's limits,
friction and armature for its joints; --payload-mass puts that mass at the flange origin (on a whole
tree, at payload.link's: -p payload.link:=LINK). Torque limits of 0 are derived as the payload check
derives them (said in the report; on a tree, give them).

Re-timing writes OUT.yaml (the same path, a point per grid point, timed time-optimally, as
``ros2 topic pub`` takes it) and prints the check of the input and of the output.
--check-only prints the check: per joint the peak torque, velocity and acceleration against
the limits, when and in which segment. On an input of a megabyte or more (about 3,000
points) its steps show on stderr (a bar with the time left on a terminal, else a line per
step). Exit status: 0; 3 when --check-only finds a limit
exceeded; 1 with one line on bad input (nothing written: the output and the plot are
written both or neither).
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m: the entry first, before the heavy imports
    from irb140_dynamics.entry import TOOL, start

    start("retime", TOOL)

import argparse
import math
import os
import sys
from dataclasses import replace
from pathlib import Path

from ..core import RigidBody, RobotModel
from ..core.errors import counted
from ..core.io.arm_source import is_one_chain
from ..core.io.atomic import write_files
from ..core.io.trajectory_file import joint_trajectory_yaml, read_joint_trajectory
from ..core.trajectories import (
    Trajectory,
    TrajectoryError,
    check_trajectory,
    retime,
    torque_limit_notes,
    trajectory_limits,
)
from .cli import ToolError, refuse_input_as_output, run
from .common import add_model_arguments, model_inputs
from .common import arm_of as _arm_of

NAME = "retime"
OVER_LIMIT = 3


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=NAME, description=__doc__.split("\n\n")[0].split(": ", 1)[1])
    p.add_argument("input", metavar="IN.yaml", help="the JointTrajectory (ros2 topic echo layout)")
    p.add_argument("output", metavar="OUT.yaml", nargs="?", help="the re-timed JointTrajectory to write")
    add_model_arguments(p, "the model and its limits (default: the package's IRB-140)")
    p.add_argument("--payload-mass", type=float, metavar="KG", help="payload at the flange origin (default: F's)")
    p.add_argument("--check-only", action="store_true", help="only check IN.yaml; write nothing but --plot")
    p.add_argument("--plot", metavar="P.png", help="per joint the use of each limit over time, before and after")
    p.add_argument("--grid", type=int, default=1000, help="grid steps over the path, about (default 1000)")
    p.add_argument(
        "--accelerations",
        action="store_true",
        help="give the output's points accelerations too (quintic; slower, see docs/trajectories.md)",
    )
    return p


def arm_of(args: argparse.Namespace):
    """The arm of the arguments (``common.arm_of``, as every tool reads it), with
    --payload-mass at the flange origin when given."""
    arm = _arm_of(args)
    if args.payload_mass is None:
        return arm
    if not (math.isfinite(args.payload_mass) and args.payload_mass >= 0):
        raise ToolError(f"--payload-mass: must be a mass >= 0 kg, got {args.payload_mass}")
    if not is_one_chain(arm.model) and not arm.given.get("payload.link"):  # else on the last joint's link, any
        raise ToolError(
            f"--payload-mass: the model is a tree ({arm.model.n} joints); name the URDF link the payload "
            "hangs on: -p payload.link:=LINK"
        )
    try:
        return replace(arm, model=arm.model.with_payload(RigidBody(args.payload_mass)))
    except ValueError as error:
        raise ToolError(f"--payload-mass: {error}") from None


def read_trajectory(path: str, model: RobotModel) -> Trajectory:
    try:
        return Trajectory.from_message(read_joint_trajectory(path), model.joint_names)
    except TrajectoryError as error:
        raise ToolError(f"{path}: {error}") from None


def write_all(files: dict[str, bytes]) -> None:
    """Every file whole or none (see ``write_files``)."""
    try:
        write_files(files)
    except OSError as error:
        raise ToolError(f"{error.filename}: cannot write: {error.strerror}") from None


def report_text(title: str, report) -> str:
    lines = [
        (
            f"{title}: {report.duration:.4f} s, {'within every limit' if report.ok else 'OVER A LIMIT'} "
            f"(worst: {report.worst.line()})"
        )
    ]
    lines += [f"  {line}" for line in report.lines()]
    return "\n".join(lines)


def main(argv=None) -> int:
    return run(NAME, lambda interrupts: _retime(parser().parse_args(sys.argv[1:] if argv is None else argv)))


def _retime(args: argparse.Namespace) -> int:
    if not args.check_only and not args.output:
        raise ToolError("OUT.yaml: missing (or give --check-only)")
    inputs = [*model_inputs(args), (args.input, Path(os.path.abspath(args.input)))]
    written = (args.plot,) if args.check_only else (args.output, args.plot)
    outputs = [(path, Path(os.path.abspath(path))) for path in written if path]
    refuse_input_as_output(inputs, outputs)
    model = arm_of(args).model
    steps = _Steps(args.input, (2 if args.check_only else 5) + bool(args.plot))
    steps("reading the input")
    tr = read_trajectory(args.input, model)
    limits = trajectory_limits(model)
    notes = list(torque_limit_notes(model, limits))
    steps("checking the input")
    before = check_trajectory(model, tr, limits)
    if args.check_only:
        if args.plot:
            steps("plotting")
        files = {args.plot: _plot(model, limits, tr, None, args)} if args.plot else {}
        write_all(files)
        steps.end()
        print("\n".join([*notes, report_text("input", before)]))
        return 0 if before.ok else OVER_LIMIT
    steps("re-timing")
    try:
        result = retime(model, tr, limits, grid=args.grid, accelerations=args.accelerations)
    except TrajectoryError as error:
        raise ToolError(f"{args.input}: {error}") from None
    steps("checking the result")
    after = check_trajectory(model, result.trajectory, limits)
    steps("writing")
    files = {args.output: joint_trajectory_yaml(result.trajectory.to_message()).encode()}
    if args.plot:
        steps("plotting")
        files[args.plot] = _plot(model, limits, tr, result.trajectory, args)
    write_all(files)
    steps.end()
    print(
        "\n".join(
            [
                *notes,
                report_text("input", before),
                report_text("re-timed", after),
                f"{counted(len(result.trajectory.t), 'point')}, {counted(result.rounds, 'round')}; wrote {', '.join(files)}",
            ]
        )
    )
    return 0


LONG_INPUT = 1_000_000  # bytes of IN.yaml (about 3,000 points): from here the work takes seconds, and says so


class _Steps:
    """The tool's steps on stderr (``tools.progress``: a bar on a terminal, else a line per
    step) for a long input; nothing for a short one, done in a moment."""

    def __init__(self, path: str, total: int):
        import os

        from .progress import Progress

        try:
            long = os.path.getsize(path) >= LONG_INPUT
        except OSError:  # (read_trajectory says why, in one line)
            long = False
        self.bar = Progress(NAME, "steps") if long else None
        self.total, self.done = total, 0

    def __call__(self, step: str) -> None:
        """``step`` begins (the ones before it are done)."""
        if self.bar is not None:
            self.bar.label = f"{NAME}: {step}"
            self.bar(self.done, self.total)
            self.done += 1

    def end(self) -> None:
        if self.bar is not None:
            self.bar.label = NAME
            self.bar(self.total, self.total)


def _plot(model, limits, before, after, args) -> bytes:
    from .retime_plot import limit_use_png, what_was_drawn

    arm = os.path.basename(args.urdf or args.params_file or "the IRB-140")
    return limit_use_png(model, limits, before, after, what_was_drawn(os.path.basename(args.input), arm, model.payload))


if __name__ == "__main__":
    from irb140_dynamics.entry import finish

    finish(main)
