"""calibrate_collision: id_node's collision thresholds from a recording of the arm's normal work.

    irb140-calibrate-collision BAG --out COLLISION.yaml [--margin 1.5] [--observer-gain 100]
        [--topic /joint_states] [--params-file ARM.yaml | --urdf ARM.urdf [--base LINK] [--tip LINK]]
        [--hold JOINT=VALUE] [-p NAME:=VALUE] [--quiet]
    (or: ros2 run irb140_dynamics calibrate_collision ..., python -m irb140_dynamics.tools.calibrate_collision ...)

BAG: a ROS 2 bag (directory, .mcap or .db3) or a CSV file of joint states with positions,
velocities and efforts, read as `identify` reads it (docs/identification.md). The arm: its
model as the nodes get it (--params-file, --urdf); the thresholds hold for that model only.

The momentum observer runs over the recording as id_node runs it (gain --observer-gain,
id_node's collision.observer_gain; a gap over 0.1 s, a repeated or older stamp restarts
it), and each joint's collision_threshold is set to --margin times the largest |r_j| it
saw: played again, the recording raises no alarm, with that margin. Prints each joint's
peak and threshold, then per direction of the base frame (+x, -x, +y, -y, +z, -z) the
force at the flange that the thresholds detect in every recorded pose, the worst pose's
('+x: 140 N (worst pose at 22.834 s, joint_3 first)'). Writes COLLISION.yaml, a parameter file with collision.observer_gain and every
<joint>.collision_threshold, to give id_node after the arm's (whole or not at all). Exit
status 0; 1 with one line naming the problem; 2 for a bad argument; 130 after Ctrl-C,
nothing written. See docs/id_node.md.
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m: the entry first, before the heavy imports
    from irb140_dynamics.entry import TOOL, start

    start("calibrate_collision", TOOL)

import argparse
import math
import sys

from irb140_dynamics.tools.cli import (
    Parser,
    ToolError,
    check_model_paths,
    input_path,
    number,
    output_file,
    refuse_input_as_output,
    run,
)
from irb140_dynamics.tools.common import add_model_arguments, arm_of, model_inputs


def parser() -> Parser:
    from irb140_dynamics.core.monitoring.collision import DEFAULT_GAIN, MAX_GAIN, MIN_GAIN
    from irb140_dynamics.core.monitoring.sensitivity import DEFAULT_MARGIN
    from irb140_dynamics.identification.recording import DEFAULT_TOPIC

    p = Parser(
        prog="calibrate_collision",
        description=__doc__.split("\n\n")[0].split(": ", 1)[1],
        epilog="\n\n".join(__doc__.split("\n\n")[2:4]),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("recording", metavar="BAG", help="ROS 2 bag (directory, .mcap, .db3) or .csv file")
    p.add_argument("--out", required=True, metavar="COLLISION.yaml", help="parameter file to write")
    p.add_argument(
        "--margin",
        type=number(1.0, 1e6, above=True),
        default=DEFAULT_MARGIN,
        help=f"threshold = MARGIN x the largest |r_j| recorded (> 1; default {DEFAULT_MARGIN:g})",
    )
    p.add_argument(
        "--observer-gain",
        type=number(MIN_GAIN, MAX_GAIN),
        default=DEFAULT_GAIN,
        metavar="K",
        help=f"the observer's gain [1/s], id_node's collision.observer_gain (default {DEFAULT_GAIN:g})",
    )
    p.add_argument("--topic", default=DEFAULT_TOPIC, help=f"JointState topic in the bag (default {DEFAULT_TOPIC})")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_model_arguments(p, "the arm's model (default: the package's IRB-140)")
    return p


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    return run("calibrate_collision", lambda interrupts: _calibrate(argv, interrupts))


def _calibrate(argv: list[str], interrupts) -> int:
    args = parser().parse_args(argv)
    recording_path = input_path(args.recording)
    check_model_paths(args)
    out = output_file(args.out)
    refuse_input_as_output([(args.recording, recording_path), *model_inputs(args)], [(args.out, out)])

    import shlex

    from irb140_dynamics.core.monitoring.sensitivity import (
        CalibrationError,
        DetectableForces,
        ResidualPeaks,
        collision_thresholds,
        usable,
    )
    from irb140_dynamics.identification.recording import Recording
    from irb140_dynamics.tools.common import reading_progress
    from irb140_dynamics.tools.outputs import Outputs

    source = arm_of(args)
    model = source.model
    passes = [None, None] if args.quiet else [reading_progress("calibrate_collision"), _poses_progress()]
    try:
        peaks = ResidualPeaks(model, args.observer_gain)
        for chunk in _chunks(Recording(args.recording, model.joint_names, args.topic), passes[0]):
            peaks.add(chunk.time, chunk.position, chunk.velocity, chunk.effort)
        if peaks.observed == 0 and peaks.no_velocity:
            raise CalibrationError(
                f"no sample has velocities ({peaks.no_velocity} without): the observer needs the measured qd"
            )
        thresholds = collision_thresholds(peaks, args.margin)
        forces = DetectableForces(model, thresholds)
        for chunk in _chunks(Recording(args.recording, model.joint_names, args.topic), passes[1]):
            observed = usable(chunk.position, chunk.velocity, chunk.effort)[0]
            forces.add(chunk.time[observed], chunk.position[observed])
    except CalibrationError as error:
        raise ToolError(f"{args.recording}: {error}") from None
    lines = summary(model, peaks, thresholds, forces.result(), args.margin, source.origin)
    with Outputs(interrupts) as outputs:
        print("\n".join(lines), flush=True)
        command = shlex.join(["calibrate_collision", *argv])
        outputs.text(out, args.out, collision_file(model, args.observer_gain, thresholds, command, lines))
        for typed in outputs.commit():
            print(f"wrote {typed}")
    return 0


def _poses_progress():
    """The second pass's bar: 'calibrate_collision: the poses of run.csv: [###   ] ...'."""
    from pathlib import Path

    from irb140_dynamics.tools.progress import Progress

    bars: dict[str, Progress] = {}

    def show(path: str, done: int, total: int) -> None:
        if path not in bars:
            bars[path] = Progress(f"calibrate_collision: the poses of {Path(path).name}", "samples")
        bars[path](done, total)

    return show


def _chunks(recording, progress):
    """The recording's chunks, the progress bar following the work done on them."""
    read = 0
    if progress:
        progress(str(recording.path), 0, recording.total)
    for chunk in recording.chunks():
        yield chunk
        read += len(chunk)
        if progress:
            progress(str(recording.path), read + sum(recording.skipped.values()), recording.total)


def summary(model, peaks, thresholds, forces, margin: float, origin) -> list[str]:
    """What the tool prints: the recording, each joint's peak and threshold, the forces."""
    restarts = ", ".join(f"{count} {kind.replace('_', ' ')}" for kind, count in sorted(peaks.restarts.items()))
    left_out = f"; {peaks.no_velocity} without velocities left out" if peaks.no_velocity else ""
    lines = [
        f"arm: {origin}",
        f"observer: gain {peaks.gain:g} 1/s over {peaks.observed} samples, {peaks.end - peaks.start:.1f} s"
        f" (restarts: {restarts or 'none'}{left_out}); times below from its first sample",
        f"collision_threshold = {margin:g} x the largest |r| recorded:",
    ]
    unit = ["N" if joint.prismatic else "N m" for joint in model.joints]
    for name, peak, at, threshold, u in zip(model.joint_names, peaks.peak, peaks.peak_time, thresholds, unit):
        lines.append(f"  {name}: largest |r| {peak:.4g} {u} at {at - peaks.start:.3f} s -> {threshold:.4g} {u}")
    lines.append("force at the flange detected in every recorded pose (base axes; the worst pose's):")
    for found in forces:
        lines.append(force_line(found, model.joint_names, peaks.start))
    return lines


def force_line(found, joint_names, start: float) -> str:
    """'+x: 9.10 N (worst pose at 3.412 s, joint_2 first)': the figure rounded up to 3
    significant digits, so that the force printed is detected too; times from ``start`` [s]."""
    if found.force is None:
        if found.time is None:
            return f"{found.direction}: no pose recorded"
        return (
            f"{found.direction}: none: at {found.undetected} recorded poses (the first at "
            f"{found.time - start:.3f} s) no joint feels a force along it"
        )
    return (
        f"{found.direction}: {rounded_up(found.force)} N (worst pose at {found.time - start:.3f} s, "
        f"{joint_names[found.joint]} first)"
    )


def rounded_up(value: float, digits: int = 3) -> str:
    """``value`` > 0 rounded up to ``digits`` significant digits (all of its whole ones)."""
    decimals = max(0, digits - 1 - math.floor(math.log10(value)))
    scale = 10.0**decimals
    up = math.ceil(value * scale - 1e-9) / scale
    return f"{up:.{decimals}f}"


def collision_file(model, gain: float, thresholds, command: str, lines: list[str]) -> str:
    from datetime import UTC, datetime

    from irb140_dynamics.core.io.params_file import parameter_file_text

    date = datetime.now(UTC).isoformat(timespec="seconds")
    comments = [
        f"collision thresholds set by irb140_dynamics `calibrate_collision` on {date}:",
        f"  {command}",
        "Give it to id_node after the arm's parameter file (--params-file ARM.yaml --params-file",
        "THIS.yaml). Units: N m (N for a sliding joint), 1/s. The thresholds hold at this observer gain.",
        "",
        *lines,
        "",
    ]
    params = {"collision.observer_gain": float(gain)}
    params.update({f"{name}.collision_threshold": float(x) for name, x in zip(model.joint_names, thresholds)})
    return parameter_file_text(params, comments)


if __name__ == "__main__":
    from irb140_dynamics.entry import finish

    finish(main)
