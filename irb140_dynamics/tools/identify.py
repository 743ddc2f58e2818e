"""identify: the arm's dynamic parameters from a recording of its joint states.

    ros2 run irb140_dynamics identify BAG [--topic /joint_states] [--params-file PRIOR.yaml]
                                          --out IDENTIFIED.yaml [--plots DIR] [--validate BAG2]

BAG: a ROS 2 bag (directory, .mcap or .db3) with sensor_msgs/JointState including effort,
or a CSV file (see docs/identification.md). Prints a progress bar while reading (stderr),
then the summary; writes IDENTIFIED.yaml, a parameter file both nodes load with
--params-file. Exit status 0, or 1 with one line naming the file and the problem.
"""

from __future__ import annotations

import argparse
import shlex
import sys

from irb140_dynamics.core.io.atomic import write_text
from irb140_dynamics.identification.pipeline import IdentificationSettings, identify
from irb140_dynamics.identification.recording import DEFAULT_TOPIC
from irb140_dynamics.identification.report import identified_file, summary
from irb140_dynamics.identification.signals import DEFAULT_CUTOFF
from irb140_dynamics.tools.common import ProgressBar, prior_model, run


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="identify", description=__doc__.split("\n\n")[0].split(": ", 1)[1])
    p.add_argument("recording", metavar="BAG", help="ROS 2 bag (directory, .mcap, .db3) or .csv file")
    p.add_argument("--out", required=True, metavar="IDENTIFIED.yaml", help="parameter file to write")
    p.add_argument("--topic", default=DEFAULT_TOPIC, help=f"JointState topic in the bag (default {DEFAULT_TOPIC})")
    p.add_argument(
        "--params-file",
        metavar="PRIOR.yaml",
        help="the prior model: kinematics, limits and starting inertials (default: the package's IRB-140)",
    )
    p.add_argument("--plots", metavar="DIR", help="write torques.png and residuals.png of the held-out data here")
    p.add_argument("--validate", metavar="BAG2", help="validate on this recording instead of the last 20 %% of BAG")
    p.add_argument(
        "--cutoff",
        type=float,
        default=DEFAULT_CUTOFF,
        help=f"filter cut-off [Hz] for smoothing and differentiation (default {DEFAULT_CUTOFF:g})",
    )
    p.add_argument(
        "--min-speed",
        type=float,
        metavar="RAD_S",
        help="leave out torque rows of joints slower than this (default 3 smoothing velocities)",
    )
    p.add_argument(
        "--held-out",
        type=float,
        default=0.2,
        metavar="FRACTION",
        help="fraction at the end of BAG held out for validation (default 0.2)",
    )
    p.add_argument(
        "--prior-weight",
        type=float,
        default=1.0,
        help="strength of the pull toward the prior (default 1; see docs/identification.md)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def main(argv=None) -> int:
    args = parser().parse_args(sys.argv[1:] if argv is None else argv)

    def body() -> int:
        prior, prior_path = prior_model(args.params_file)
        settings = IdentificationSettings(
            topic=args.topic,
            cutoff=args.cutoff,
            min_speed=args.min_speed,
            held_out=args.held_out,
            prior_weight=args.prior_weight,
        )
        progress = None if args.quiet else ProgressBar()
        result = identify(prior, args.recording, settings, validate=args.validate, progress=progress)
        print(f"prior: {prior_path}")
        print(summary(result))
        command = shlex.join(["identify", *(sys.argv[1:] if argv is None else argv)])
        write_text(args.out, identified_file(result, command))
        print(f"wrote {args.out}")
        if args.plots:
            from irb140_dynamics.identification.plots import write_plots

            for path in write_plots(result, args.plots):
                print(f"wrote {path}")
        return 0

    return run("identify", body)


if __name__ == "__main__":
    sys.exit(main())
