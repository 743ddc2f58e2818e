"""excitation: a periodic trajectory that makes the arm's dynamic parameters identifiable.

    ros2 run irb140_dynamics excitation --out FILE [--params-file F] [--rate HZ] [--period S]
                                        [--harmonics K] [--periods P] [--seed N] [--iterations N]

Writes FILE, a trajectory_msgs/JointTrajectory in YAML (the form `ros2 topic pub` takes),
and prints the condition number of the base regressor it reached (also a comment in FILE).
The trajectory stays within the model's position (less a margin), velocity and
acceleration limits, starts and ends at rest at its first point, and repeats seamlessly.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from irb140_dynamics.core.io.atomic import write_text
from irb140_dynamics.core.io.trajectory_file import joint_trajectory_text
from irb140_dynamics.identification.base import find_base_parameters
from irb140_dynamics.identification.excitation import (
    DEFAULT_HARMONICS,
    DEFAULT_MARGIN,
    DEFAULT_PERIOD,
    check_limits,
    optimise_excitation,
)
from irb140_dynamics.tools.common import ToolError, prior_model, run

SHELL_ARGUMENT_LIMIT = 128 * 1024  # bytes: Linux's MAX_ARG_STRLEN


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="excitation", description=__doc__.split("\n\n")[0].split(": ", 1)[1])
    p.add_argument("--out", required=True, metavar="FILE", help="JointTrajectory YAML file to write")
    p.add_argument("--params-file", metavar="F", help="the model and its limits (default: the package's IRB-140)")
    p.add_argument("--rate", type=float, default=20.0, metavar="HZ", help="points per second (default 20)")
    p.add_argument(
        "--period", type=float, default=DEFAULT_PERIOD, metavar="S", help=f"period [s] (default {DEFAULT_PERIOD:g})"
    )
    p.add_argument(
        "--harmonics",
        type=int,
        default=DEFAULT_HARMONICS,
        metavar="K",
        help=f"Fourier harmonics per joint (default {DEFAULT_HARMONICS})",
    )
    p.add_argument("--periods", type=int, default=1, metavar="P", help="periods written (default 1)")
    p.add_argument(
        "--margin",
        type=float,
        default=DEFAULT_MARGIN,
        help=f"fraction of each position range kept free at both ends (default {DEFAULT_MARGIN:g})",
    )
    p.add_argument("--seed", type=int, default=0, help="random start of the optimisation (default 0)")
    p.add_argument("--iterations", type=int, default=40, help="optimiser iterations (default 40)")
    return p


def main(argv=None) -> int:
    args = parser().parse_args(sys.argv[1:] if argv is None else argv)

    def body() -> int:
        if not args.rate > 0 or args.periods < 1 or not 0 <= args.margin < 0.5 or args.iterations < 0:
            raise ToolError("--rate must be > 0, --periods >= 1, --margin within [0, 0.5), --iterations >= 0")
        model, path = prior_model(args.params_file)
        base = find_base_parameters(model)
        print(f"model: {path}; {base.count} base parameters; optimising ({args.iterations} iterations)...")
        result = optimise_excitation(
            model, args.period, args.harmonics, args.seed, args.iterations, margin=args.margin, base=base
        )
        trajectory = result.trajectory
        problems = check_limits(model, trajectory, args.rate)
        if problems:  # cannot happen by construction; refuse rather than write a bad file
            raise ToolError("the trajectory leaves the limits: " + "; ".join(problems))
        times = trajectory.times(args.rate, args.periods)
        Q, QD, QDD = trajectory.evaluate(times)
        QD[np.abs(QD) < 1e-12], QDD[np.abs(QDD) < 1e-12] = 0.0, 0.0
        comments = [
            f"Excitation trajectory for `identify` (irb140_dynamics), model {path}",
            f"condition number of the base regressor: {result.condition_number:.2f} (random start: "
            f"{result.start_condition_number:.2f})",
            f"{args.periods} x {args.period:g} s period, {args.harmonics} harmonics, {args.rate:g} Hz, "
            f"{len(times)} points; starts and ends at rest at the first point",
            "Move the arm to the first point first. Publish it, e.g.:",
            "  ros2 topic pub --once /joint_trajectory_controller/joint_trajectory "
            'trajectory_msgs/msg/JointTrajectory "$(cat FILE)"   (or --yaml-file FILE)',
            "and record: ros2 bag record /joint_states",
        ]
        text = joint_trajectory_text(model.joint_names, times, Q, QD, QDD, comments)
        write_text(args.out, text)
        print(f"condition number: {result.condition_number:.2f} (random start {result.start_condition_number:.2f})")
        print(
            f"wrote {args.out}: {len(times)} points over {times[-1]:g} s; start at "
            f"[{', '.join(f'{x:.4f}' for x in Q[0])}] rad"
        )
        if len(text) > SHELL_ARGUMENT_LIMIT:
            print(
                f'note: {len(text) // 1024} kB is too long for one shell argument ("$(cat {args.out})"): '
                "publish it with --yaml-file, or lower --rate"
            )
        return 0

    return run("excitation", body)


if __name__ == "__main__":
    sys.exit(main())
