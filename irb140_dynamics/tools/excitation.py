"""excitation: a periodic trajectory that makes the arm's dynamic parameters identifiable.

    irb140-excitation --out FILE [--params-file F | --urdf FILE [--base L] [--tip L]] [--hold J=V]
                      [-p NAME:=VALUE] [--rate HZ] [--period S]
                      [--harmonics K] [--periods P] [--seed N] [--iterations N]
                      [--payload [--pose Q1,...,Qn] [--effort-noise N|P%] [--record-rate HZ]]
    (or: ros2 run irb140_dynamics excitation ..., python -m irb140_dynamics.tools.excitation ...)

Writes FILE, a trajectory_msgs/JointTrajectory in YAML (the form `ros2 topic pub` takes),
and prints the condition number of the base regressor it reached (also a comment in FILE).
The trajectory stays within the model's position (less a margin), velocity and
acceleration limits, and its torques (rnea, with the model's payload) within the torque
limits (the motion of the joints sharing a torque scaled down toward the pose that needs the
least torque at rest, when they need it; refused when no pose within the ranges can be
held), starts and ends at rest at its first point,
and repeats seamlessly. On a model with mimic joints it moves the independent joints (the
mimic joints follow them, within their own limits).
Every argument and FILE's folder are checked before the work; FILE is written whole or
not at all. The optimisation's progress goes to stderr (a bar with the time left on a
terminal, else a line per 10 %). Exit status 0; 1 with one line; 2 for a bad argument; 130 after Ctrl-C.

With --payload, a load identification motion for `identify --payload-only`: the last three
joints move (each over more than 0.1 rad), the others hold --pose (default: chosen with the
motion), at most 30 s in all (default: as many periods as fit, the period chosen unless
given); designed for the payload's ten parameters at the stated --effort-noise, it prints
(and writes in FILE's header) each parameter's expected standard deviation, and the
condition number of the payload's noise-weighted regressor (see docs/load.md).
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m: the entry first, before the heavy imports
    from irb140_dynamics.entry import TOOL, start

    start("excitation", TOOL)

import argparse
import sys

from irb140_dynamics.core.errors import counted
from irb140_dynamics.tools.cli import (
    Parser,
    ToolError,
    check_model_paths,
    number,
    output_file,
    refuse_input_as_output,
    run,
)
from irb140_dynamics.tools.common import add_model_arguments, arm_of, model_inputs

MAX_POINTS = 1_000_000  # points written: 100 MB of YAML
POINTS_PER_CYCLE = 4  # of the highest harmonic: fewer points do not show the motion
SHELL_ARGUMENT_LIMIT = 128 * 1024  # bytes: Linux's MAX_ARG_STRLEN
PUBLISH = "  ros2 topic pub --once /joint_trajectory_controller/joint_trajectory trajectory_msgs/msg/JointTrajectory {argument}"


def parser() -> Parser:
    from irb140_dynamics.identification.excitation import DEFAULT_HARMONICS, DEFAULT_MARGIN, DEFAULT_PERIOD
    from irb140_dynamics.identification.payload_excitation import (
        DEFAULT_PAYLOAD_HARMONICS,
        DEFAULT_RECORD_RATE,
        MAX_PAYLOAD_DURATION,
        PERIODS,
    )

    p = Parser(prog="excitation", description=__doc__.split("\n\n")[0].split(": ", 1)[1])
    p.add_argument("--out", required=True, metavar="FILE", help="JointTrajectory YAML file to write")
    p.add_argument(
        "--rate", type=number(0.0, 1e4, above=True), default=20.0, metavar="HZ", help="points per second (default 20)"
    )
    p.add_argument(
        "--period",
        type=number(0.0, 1e4, above=True),
        metavar="S",
        help=f"period [s] (default {DEFAULT_PERIOD:g}; with --payload chosen among "
        f"{', '.join(f'{T:g}' for T in PERIODS)})",
    )
    p.add_argument(
        "--harmonics",
        type=number(1, 50, integer=True),
        metavar="K",
        help=f"Fourier harmonics per joint (default {DEFAULT_HARMONICS}; {DEFAULT_PAYLOAD_HARMONICS} with --payload)",
    )
    p.add_argument(
        "--periods",
        type=number(1, 10_000, integer=True),
        metavar="P",
        help=f"periods written (default 1; with --payload as many as {MAX_PAYLOAD_DURATION:g} s hold)",
    )
    p.add_argument(
        "--margin",
        type=number(0.0, 0.49),
        default=DEFAULT_MARGIN,
        help=f"fraction of each position range kept free at both ends, below 0.5 (default {DEFAULT_MARGIN:g})",
    )
    p.add_argument(
        "--seed",
        type=number(0, 2**32 - 1, integer=True),
        default=0,
        help="random start of the optimisation (default 0)",
    )
    p.add_argument(
        "--iterations",
        type=number(0, 10_000, integer=True),
        default=40,
        help="optimiser iterations (default 40; --payload: for each of the 2 best periods, a quarter for every period)",
    )
    p.add_argument(
        "--payload",
        action="store_true",
        help="a wrist motion that excites a payload's mass, CoM and inertia (identify --payload-only)",
    )
    p.add_argument(
        "--pose",
        type=_pose,
        metavar="Q1,...,Qn",
        help="with --payload: the pose [rad] the joints before the wrist hold, one value per joint within its "
        "range (the wrist's are not used; default: mid-range)",
    )
    p.add_argument(
        "--effort-noise",
        type=_effort_noise,
        metavar="N|P%",
        help="with --payload: the recorded efforts' noise, one standard deviation per sample, in N m on every "
        "joint (0.05) or a percentage of each joint's torque limit (1%%; of its peak torque where it has none); "
        "default 1%%",
    )
    p.add_argument(
        "--record-rate",
        type=number(0.0, 1e5, above=True),
        metavar="HZ",
        help=f"with --payload: the rate the joint states will be recorded at (default {DEFAULT_RECORD_RATE:g})",
    )
    add_model_arguments(p, "the model and its limits (default: the package's IRB-140)")
    return p


def _pose(text: str) -> list[float]:
    import math

    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None
    if not all(math.isfinite(x) for x in values):
        raise argparse.ArgumentTypeError(f"expected finite numbers, got {text!r}")
    return values


def _effort_noise(text: str):
    from irb140_dynamics.identification.effort_noise import EffortNoise

    try:
        return EffortNoise.parse(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error).removeprefix("effort noise: ")) from None


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    return run("excitation", lambda interrupts: _excitation(parser().parse_args(argv), interrupts))


def _excitation(args: argparse.Namespace, interrupts) -> int:
    from irb140_dynamics.identification.excitation import DEFAULT_HARMONICS, DEFAULT_PERIOD
    from irb140_dynamics.identification.payload_excitation import (
        DEFAULT_PAYLOAD_HARMONICS,
        MAX_PAYLOAD_DURATION,
        PERIODS,
        period_choices,
        recorded,
    )

    for option in ("pose", "effort_noise", "record_rate"):
        if getattr(args, option) is not None and not args.payload:
            raise ToolError(f"--{option.replace('_', '-')}: only with --payload")
    if args.harmonics is None:
        args.harmonics = DEFAULT_PAYLOAD_HARMONICS if args.payload else DEFAULT_HARMONICS
    if args.payload:
        choices = period_choices(args.period, args.periods)
        if not choices:
            shortest = recorded(args.period or min(PERIODS), args.periods)
            raise ToolError(
                f"--period x --periods: a payload motion lasts at most {MAX_PAYLOAD_DURATION:g} s, got {shortest:g} s"
            )
        longest = max(recorded(T, args.periods) for T in choices)
        period_bound = min(choices)  # the fewest points per period: the check below
        total = longest
    else:
        args.period = args.period or DEFAULT_PERIOD
        args.periods = args.periods or 1
        period_bound, total = args.period, args.period * args.periods
    points = args.rate * total
    if points > MAX_POINTS:
        raise ToolError(f"--rate x --period x --periods gives {points:.3g} points, more than {MAX_POINTS:,}")
    if args.rate * period_bound < POINTS_PER_CYCLE * args.harmonics:
        raise ToolError(
            f"--rate x --period gives {args.rate * period_bound:.3g} points per period, fewer than "
            f"{POINTS_PER_CYCLE * args.harmonics} ({POINTS_PER_CYCLE} per cycle of harmonic {args.harmonics}): "
            "raise --rate"
        )
    check_model_paths(args)
    out = output_file(args.out)
    refuse_input_as_output(model_inputs(args), [(args.out, out)])

    import numpy as np

    from irb140_dynamics.core.io.trajectory_file import commented, joint_trajectory_text
    from irb140_dynamics.identification.base import find_base_parameters
    from irb140_dynamics.identification.excitation import check_limits, optimise_excitation
    from irb140_dynamics.tools.outputs import Outputs

    source = arm_of(args, chain_for="excitation --payload" if args.payload else None)
    model, path = source.model, source.origin
    expectation = []
    if args.payload:
        from irb140_dynamics.identification.payload_excitation import with_assumed_accelerations

        result, regressor = _payload_excitation(model, path, args), "the payload's noise-weighted regressor"
        model = with_assumed_accelerations(model)  # the limits it was designed within, checked below
        args.period = result.trajectory.period
        args.periods = int(round(result.duration / args.period))
        expectation = result.expectation()
        print("\n".join(expectation), flush=True)
    else:
        base = find_base_parameters(model)
        print(
            f"model: {path}; {counted(base.count, 'base parameter')}; "
            f"optimising ({counted(args.iterations, 'iteration')})...",
            flush=True,
        )
        result = optimise_excitation(
            model,
            args.period,
            args.harmonics,
            args.seed,
            args.iterations,
            margin=args.margin,
            base=base,
            progress=_progress(),
        )
        regressor = "the base regressor"
        if result.torque is not None:
            expectation = [torque_scaling_line(model, result.torque)]
            print(expectation[0], flush=True)
    trajectory = result.trajectory
    problems = check_limits(model, trajectory, args.rate)
    if problems:  # by construction only a --payload motion's torques: refuse rather than write a bad file
        raise ToolError("the trajectory leaves the limits: " + "; ".join(problems))
    times = trajectory.times(args.rate, args.periods)
    Q, QD, QDD = trajectory.evaluate(times)
    QD[np.abs(QD) < 1e-12], QDD[np.abs(QDD) < 1e-12] = 0.0, 0.0
    comments = [
        f"Excitation trajectory for `identify{' --payload-only' if args.payload else ''}` (irb140_dynamics), "
        f"model {path}",
        f"condition number of {regressor}: {result.condition_number:.2f} (random start: "
        f"{result.start_condition_number:.2f})",
        f"{args.periods} x {args.period:g} s period, {counted(args.harmonics, 'harmonic')}, {args.rate:g} Hz, "
        f"{counted(len(times), 'point')}; starts and ends at rest at the first point",
        "Move the arm to the first point first. Publish it, e.g.:",
        PUBLISH.format(argument='"$(cat FILE)"   (or --yaml-file FILE)'),
        "and record: ros2 bag record /joint_states",
        *expectation,
    ]
    points = joint_trajectory_text(model.joint_names, times, Q, QD, QDD)  # written once: 2 MB takes a second
    text = commented(comments, points)
    if len(text) > SHELL_ARGUMENT_LIMIT:  # too long for "$(cat FILE)": the header says the way that works
        comments[comments.index("Move the arm to the first point first. Publish it, e.g.:") + 1] = PUBLISH.format(
            argument="--yaml-file FILE   (too long for one shell argument)"
        )
        text = commented(comments, points)
    with Outputs(interrupts) as outputs:
        outputs.text(out, args.out, text)
        print(  # before the commit: `| head` stops the tool with nothing written
            f"condition number: {result.condition_number:.2f} (random start {result.start_condition_number:.2f})",
            flush=True,
        )
        outputs.commit()
    print(
        f"wrote {args.out}: {counted(len(times), 'point')} over {times[-1]:g} s; start at "
        f"[{', '.join(f'{x:.4f}' for x in Q[0])}] rad"
    )
    if len(text) > SHELL_ARGUMENT_LIMIT:
        print(
            f'note: {len(text) // 1024} kB is too long for one shell argument ("$(cat {args.out})"): '
            "publish it with --yaml-file, or lower --rate"
        )
    return 0


def torque_scaling_line(model, torque) -> str:
    """What the torque limits did to the motion (``identification.torque_limits.TorqueScaling``)."""
    needed = ", ".join(f"{name} {peak:.4g} N m (limit {limit:g})" for name, peak, limit in torque.needed)
    scaled = ", ".join(
        f"{name} {100 * a:.0f} % toward {q:.3f}"
        for name, a, q in zip(model.joint_names, torque.amplitudes, torque.pose)
        if a < 1.0
    )
    return f"scaled down for the torque limits (the full motion needed {needed}): {scaled} rad"


def _payload_excitation(model, path: str, args: argparse.Namespace):
    from irb140_dynamics.identification.payload_excitation import (
        DEFAULT_EFFORT_NOISE,
        DEFAULT_RECORD_RATE,
        optimise_payload_excitation,
        payload_limits,
        wrist,
    )

    if args.pose is not None and len(args.pose) != model.n:
        raise ToolError(f"--pose: expected {model.n} joint positions, got {len(args.pose)}")
    try:
        payload_limits(model, args.margin, args.pose)  # the pose refused before the work
    except ValueError as error:
        message = str(error)
        raise ToolError(f"--{message}" if message.startswith("pose:") else message) from None
    moving = wrist(model)
    print(
        f"model: {path}; payload motion of {', '.join(model.joint_names[j] for j in moving)}; "
        f"optimising ({counted(args.iterations, 'iteration')})...",
        flush=True,
    )
    try:
        result = optimise_payload_excitation(
            model,
            args.period,
            args.harmonics,
            args.seed,
            args.iterations,
            margin=args.margin,
            pose=args.pose,
            noise=args.effort_noise or DEFAULT_EFFORT_NOISE,
            rate=args.record_rate or DEFAULT_RECORD_RATE,
            periods=args.periods,
            progress=_progress(),
        )
    except ValueError as error:
        message = str(error)
        raise ToolError(f"--{message}" if message.startswith("pose:") else message) from None
    held = [j for j in range(model.n) if j not in moving]
    trajectory = result.trajectory
    print(
        f"{len(moving)} joints moving {trajectory.period:g} s periods for {result.duration:g} s"
        + (f", the others held at [{', '.join(f'{trajectory.q0[j]:.4f}' for j in held)}] rad" if held else "")
        + ("" if args.pose is not None else " (chosen: --pose holds another)"),
        flush=True,
    )
    return result


def _progress():
    """The optimiser's iterations on stderr (see ``tools.progress``)."""
    from irb140_dynamics.tools.progress import Progress

    return Progress("excitation: optimising", "iterations")


if __name__ == "__main__":
    from irb140_dynamics.entry import finish

    finish(main)
