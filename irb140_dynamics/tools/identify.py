"""identify: the arm's dynamic parameters from a recording of its joint states.

    irb140-identify BAG --out IDENTIFIED.yaml [--topic /joint_states]
        [--params-file PRIOR.yaml | --urdf PRIOR.urdf [--base LINK] [--tip LINK]] [--hold JOINT=VALUE] [-p NAME:=VALUE]
        [--urdf-out IDENTIFIED.urdf] [--plots DIR] [--validate BAG2] [--offsets]
    irb140-identify --payload-only --params-file ARM.yaml BAG --out LOAD.yaml
    (or: ros2 run irb140_dynamics identify ..., python -m irb140_dynamics.tools.identify ...)

BAG: a ROS 2 bag (directory, .mcap or .db3) with sensor_msgs/JointState including effort,
or a CSV file (see docs/identification.md). Rest is trimmed at both ends by itself: the
recording may start before the motion and stop after it. A fit point *moves* when at
least one joint is fast enough to use its torque row (--min-speed); the last --held-out
fraction of the moving fit points is held out for validation (or all of --validate BAG2),
the rest fitted; the report says where the motion and the held-out part are.

Every argument and output path is checked before the recording is read. Prints a progress
bar while reading (stderr), then the summary; writes IDENTIFIED.yaml (a parameter file
both nodes load with --params-file), when the prior is a URDF (or with --urdf-out) the
identified arm as a URDF (IDENTIFIED.urdf beside it by default: the prior's kinematics and
limits, the identified inertials and friction), and, with --plots, DIR/torques.png and
DIR/residuals.png: all of them or none (each written to a temporary file beside it,
renamed at the end). Exit status 0; 1 with one line naming the file and the problem; 2
for a bad argument; 130 after Ctrl-C, nothing written.

With --payload-only, only the payload is fitted (mass, CoM in the flange frame, inertia
about its CoM), the arm's own parameters taken from ARM.yaml (or --urdf) as they are; a
recording of `excitation --payload` (see docs/load.md). LOAD.yaml is ARM.yaml's model with
payload.* identified.
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m: the entry first, before the heavy imports
    from irb140_dynamics.entry import TOOL, start

    start("identify", TOOL)

import argparse
import sys
from pathlib import Path

from irb140_dynamics.tools.cli import (
    Parser,
    ToolError,
    check_model_paths,
    files_in,
    input_path,
    number,
    output_directory,
    output_file,
    refuse_input_as_output,
    run,
)
from irb140_dynamics.tools.common import add_model_arguments, arm_of, model_inputs

DEFAULT_HELD_OUT = 0.2
DEFAULT_PRIOR_WEIGHT = 1.0
PLOTS = ("torques.png", "residuals.png")  # what identification.plots.write_plots writes


def parser() -> Parser:
    from irb140_dynamics.identification.recording import DEFAULT_TOPIC  # light: no NumPy work at import
    from irb140_dynamics.identification.signals import DEFAULT_CUTOFF

    p = Parser(
        prog="identify",
        description=__doc__.split("\n\n")[0].split(": ", 1)[1],
        epilog="\n\n".join(__doc__.split("\n\n")[2:4]),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("recording", metavar="BAG", help="ROS 2 bag (directory, .mcap, .db3) or .csv file")
    p.add_argument("--out", required=True, metavar="IDENTIFIED.yaml", help="parameter file to write")
    p.add_argument("--topic", default=DEFAULT_TOPIC, help=f"JointState topic in the bag (default {DEFAULT_TOPIC})")
    p.add_argument("--plots", metavar="DIR", help="write torques.png and residuals.png of the held-out data here")
    p.add_argument(
        "--validate",
        metavar="BAG2",
        help="validate on this recording (rest trimmed) instead of the last --held-out of BAG's moving fit points",
    )
    p.add_argument(
        "--cutoff",
        type=number(0.0, 1e6, above=True),
        default=DEFAULT_CUTOFF,
        metavar="HZ",
        help=f"filter cut-off [Hz] for smoothing and differentiation (default {DEFAULT_CUTOFF:g})",
    )
    p.add_argument(
        "--min-speed",
        type=number(0.0, 1e3),
        metavar="RAD_S",
        help="a joint's torque row is used (and the point moves) from this speed on "
        "(default 3 smoothing velocities of the prior; 0: keep every row)",
    )
    p.add_argument(
        "--held-out",
        type=number(0.0, 1.0, above=True),
        metavar="FRACTION",
        help=f"fraction of BAG's moving fit points, at its end, held out (default {DEFAULT_HELD_OUT:g})",
    )
    p.add_argument(
        "--prior-weight",
        type=number(0.0, 1e6, above=True),
        metavar="W",
        help=f"strength of the pull toward the prior (default {DEFAULT_PRIOR_WEIGHT:g}; see docs/identification.md)",
    )
    p.add_argument(
        "--offsets", action="store_true", help="fit a constant torque offset per joint (a sensor's bias; default off)"
    )
    p.add_argument(
        "--urdf-out",
        metavar="FILE",
        help="the identified arm as URDF (default with a URDF prior: IDENTIFIED.urdf beside --out)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--payload-only",
        action="store_true",
        help="fit only the payload (mass, CoM, inertia), the arm's parameters as the model gives them",
    )
    add_model_arguments(
        p, "the prior model: kinematics, limits and starting inertials (default: the package's IRB-140)"
    )
    return p


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    return run("identify", lambda interrupts: _identify(argv, interrupts))


def _identify(argv: list[str], interrupts) -> int:
    args = parser().parse_args(argv)
    if args.payload_only:
        from irb140_dynamics.tools.identify_payload import identify_payload

        return identify_payload(args, argv, interrupts)
    args.held_out = DEFAULT_HELD_OUT if args.held_out is None else args.held_out  # None: not given
    args.prior_weight = DEFAULT_PRIOR_WEIGHT if args.prior_weight is None else args.prior_weight
    if not args.held_out < 1.0:
        raise ToolError(f"--held-out: must be < 1, got {args.held_out:g}")
    recording = input_path(args.recording)
    validate = input_path(args.validate) if args.validate else None
    check_model_paths(args)
    out = output_file(args.out)
    urdf_out = output_file(args.urdf_out) if args.urdf_out else None
    plots = output_directory(args.plots) if args.plots else None
    plot_files = files_in(plots, args.plots, PLOTS) if plots is not None else []
    inputs = [(args.recording, recording), (args.validate, validate), *model_inputs(args)]
    outputs = [(args.out, out), (args.urdf_out, urdf_out), (args.plots, plots), *plot_files]
    refuse_input_as_output(inputs, outputs)

    import shlex

    from irb140_dynamics.identification.pipeline import IdentificationSettings, identify
    from irb140_dynamics.identification.report import identified_file, identified_urdf, summary
    from irb140_dynamics.tools.common import reading_progress
    from irb140_dynamics.tools.outputs import Outputs

    source = arm_of(args)
    prior, prior_path = source.model, source.origin
    if urdf_out is None and source.urdf is not None:
        args.urdf_out = str(Path(args.out).with_suffix(".urdf"))
        urdf_out = output_file(args.urdf_out)
        refuse_input_as_output(inputs, [(args.urdf_out, urdf_out)])
    settings = IdentificationSettings(
        topic=args.topic,
        cutoff=args.cutoff,
        min_speed=args.min_speed,
        held_out=args.held_out,
        prior_weight=args.prior_weight,
        offsets=args.offsets,
    )
    progress = None if args.quiet else reading_progress("identify")
    with Outputs(interrupts) as outputs:
        result = identify(prior, args.recording, settings, validate=args.validate, progress=progress)
        print(f"prior: {prior_path}")
        print(summary(result), flush=True)
        command = shlex.join(["identify", *argv])
        outputs.text(out, args.out, identified_file(result, command))
        if urdf_out is not None:
            outputs.text(urdf_out, args.urdf_out, identified_urdf(result, source.urdf_text, command))
        if plots is not None:
            from irb140_dynamics.identification.plots import write_plots

            outputs.directory(plots, args.plots)
            shown = {path.name: typed for typed, path in plot_files}
            arm = f"{source.robot_name} from {Path(source.origin).name}"
            names = write_plots(result, lambda name, save: outputs.stage(plots / name, shown[name], save), arm)
            if not names:
                print(f"no held-out points to plot: nothing written in {args.plots}")
        for typed in outputs.commit():
            print(f"wrote {typed}")
    return 0


if __name__ == "__main__":
    from irb140_dynamics.entry import finish

    finish(main)
