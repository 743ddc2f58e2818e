"""load_diagram: the arm's load diagram, the largest payload per centre-of-mass position.

    irb140-load-diagram --out DIR [--params-file F | --urdf U [--base B] [--tip T]] [--hold J=V] [-p NAME:=VALUE]
                        [--z-max 0.3] [--l-max 0.2] [--step 0.01] [--rated-mass 6.0]
    (or: ros2 run irb140_dynamics load_diagram ..., python -m irb140_dynamics.tools.load_diagram ...)

For each CoM position on the grid z = 0, step, ..., z-max (along the flange's z axis) and
l = 0, step, ..., l-max (off it, in any direction about it) [m], the largest payload mass
[kg] the arm holds at rest in every pose within its joint ranges and every direction,
against its torque limits: each joint's torque_limit where given (a URDF's effort), else
derived as the payload check derives them (the worst static torque of the rated payload,
--rated-mass kg at the flange origin). The flange frame is the one payload.com is given in.
Writes DIR/load_diagram.csv (z_m, l_m, max_mass_kg, status, limiting_joint, reason: a
``proven`` mass is a certified lower bound of the true maximum; an ``unproven`` one the mass
a pose found, above which nothing holds, or empty) and DIR/load_diagram.png (mass contours
over the Z-L plane, the rated mass's curve in bold), both or neither, and prints one line
Meanwhile its progress on stderr: a bar with the points done and the time left on a
terminal, else a line per 10 %.
The grid has at most 20,000 points (MAX_POINTS): a step that needs more is refused from
its size alone, before any work, naming --step.
Exit status 0; 1 with one line (a bad file, nothing written); 2 for a bad argument; with
--check 0 inside, 1 outside (or not proven), 2 for any bad input or file; 130 after Ctrl-C.
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m: the entry first, before the heavy imports
    from irb140_dynamics.entry import TOOL, start

    start("load_diagram", TOOL)

import math
import os
import sys

from irb140_dynamics.tools.cli import (
    Parser,
    ToolError,
    check_model_paths,
    errors_as_bad_input,
    files_in,
    number,
    output_directory,
    refuse_input_as_output,
    run,
)
from irb140_dynamics.tools.common import add_model_arguments, arm_of

NAME = "load_diagram"
MAX_MASS = 1e6  # kg: the model's own cap of a mass
MAX_POINTS = 20_000  # grid points: a diagram beyond this is a typo of --step
FILES = ("load_diagram.csv", "load_diagram.png")


def parser() -> Parser:
    p = Parser(prog=NAME, description=__doc__.split("\n\n")[0].split(": ", 1)[1])
    p.add_argument("--out", metavar="DIR", help="the folder to write the CSV and PNG into")
    add_model_arguments(p)
    p.add_argument("--z-max", type=number(0.0, 10.0), default=0.3, metavar="M", help="Z's last value [m] (0.3)")
    p.add_argument("--l-max", type=number(0.0, 10.0), default=0.2, metavar="M", help="L's last value [m] (0.2)")
    p.add_argument("--step", type=number(0.0, 10.0, above=True), default=0.01, metavar="M", help="grid step [m] (0.01)")
    p.add_argument(
        "--rated-mass",
        type=number(0.0, 1e6, above=True),
        metavar="KG",
        help="the arm's rated payload, over its rated_payload.mass: limits not given are derived from it, "
        "its curve is marked (without either: limits derived from 6 kg, nothing marked)",
    )
    p.add_argument(
        "--check",
        nargs=3,
        type=number(),
        metavar=("MASS", "Z", "L"),
        help="only say whether a tool of MASS kg with its CoM at Z, L [m] is inside the proven diagram "
        "(exit 0) or not (1), with the margin and the limiting joint (bad input: 2); --out is then not needed",
    )
    return p


def grid_size(maximum: float, step: float) -> float:
    """How many values ``grid(maximum, step)`` has, counted without making them (a float:
    inf where the step is too small to count in; the size is checked before any work)."""
    count = maximum / step
    if not count < 1e15:  # (inf: a step too small to divide by)
        return math.inf
    values = math.floor(count + 1e-9) + 1
    return values + (maximum - (values - 1) * step > 1e-9 * step)


def grid(maximum: float, step: float):
    """0, step, ..., maximum (its last value included: a maximum within 1e-9 steps of the grid)."""
    import numpy as np

    count = math.floor(maximum / step + 1e-9)
    values = np.arange(count + 1) * step
    if maximum - values[-1] > 1e-9 * step:
        values = np.append(values, maximum)
    return values


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    return run(NAME, lambda interrupts: _diagram(args, interrupts))


def _diagram(argv: list[str], interrupts) -> int:
    arguments = parser()
    args = arguments.parse_args(argv)
    if args.check is None:
        return _answer(arguments, args, interrupts)
    with errors_as_bad_input():  # status 1 is the check's answer: outside
        return _answer(arguments, args, interrupts)


def _answer(arguments: Parser, args, interrupts) -> int:
    """The diagram written, or the --check answered (``args`` parsed by ``arguments``)."""
    sizes = grid_size(args.z_max, args.step), grid_size(args.l_max, args.step)
    if sizes[0] * sizes[1] > MAX_POINTS:  # a bad argument, refused before any work: a tiny step costs nothing
        shown = " x ".join(f"{s:.0f}" if math.isfinite(s) else "too many" for s in sizes)
        arguments.error(f"--step {args.step:g}: {shown} points, more than {MAX_POINTS:,}: give a larger step")
    if args.check is None and args.out is None:
        arguments.error("the following arguments are required: --out (or --check MASS Z L)")
    if args.check is not None:
        mass, z, l = args.check
        if not (0.0 <= mass <= MAX_MASS and abs(z) <= 10.0 and 0.0 <= l <= 10.0):
            arguments.error(
                f"--check {mass:g} {z:g} {l:g}: MASS must be within 0..{MAX_MASS:g} kg, Z within -10..10 m "
                "and L (a distance off the axis) within 0..10 m"
            )
    check_model_paths(args)
    out = output_directory(args.out) if args.check is None else None
    files = None
    if out is not None:
        from irb140_dynamics.tools.common import model_inputs

        files = files_in(out, args.out, FILES)
        refuse_input_as_output(model_inputs(args), files)
    z, l = grid(args.z_max, args.step), grid(args.l_max, args.step)

    from irb140_dynamics.core.payload import derive_torque_limits
    from irb140_dynamics.core.payload.diagram import load_diagram
    from irb140_dynamics.tools.load_diagram_plot import diagram_csv, diagram_png
    from irb140_dynamics.tools.outputs import Outputs

    source = arm_of(args, chain_for="load_diagram")
    try:
        given = source.given
        if not (args.params_file or args.urdf):  # the package's own arm: its file states its rated payload
            from irb140_dynamics.core.io.params_file import read_parameter_file

            given = {**read_parameter_file(source.origin), **given}
        rated, stated = rated_payload(given, args.rated_mass)
    except ValueError as error:
        raise ToolError(str(error).splitlines()[0]) from None
    model = source.model
    limits = derive_torque_limits(model, rated)
    if args.check is not None:
        return _check(model, limits.values, *args.check)
    diagram = load_diagram(model, limits.values, z, l, _progress(z.size, l.size), _workers(z.size))
    rated_mass = rated.mass if stated else None
    csv, png = diagram_csv(diagram).encode(), diagram_png(diagram, os.path.basename(source.origin), rated_mass)
    with Outputs(interrupts) as outputs:
        outputs.directory(out, args.out)
        for (typed, path), data in zip(files, (csv, png)):
            outputs.stage(path, typed, lambda stream, data=data: stream.write(data))
        written = outputs.commit()
    print(_summary(diagram, written))
    return 0


def rated_payload(parameters, rated_mass: float | None):
    """(the rated payload, whether the arm states it): ``--rated-mass`` kg, else the
    parameters' rated_payload.mass (and .com), else the default the nodes derive limits from
    (6 kg at the flange origin), not stated. ValueError in one line for a bad parameter."""
    from irb140_dynamics.core.model.rigid_body import RigidBody
    from irb140_dynamics.core.payload import RATED_PAYLOAD

    com = parameters.get("rated_payload.com", RATED_PAYLOAD.com)
    if rated_mass is not None:
        return RigidBody.validated("rated_payload", rated_mass, com), True
    if "rated_payload.mass" in parameters:
        return RigidBody.validated("rated_payload", parameters["rated_payload.mass"], com), True
    return RATED_PAYLOAD, False


def _check(model, limits, mass: float, z: float, l: float) -> int:
    """One line: is ``mass`` kg at (z, l) inside the proven diagram; exit 0 inside, 1 not."""
    from irb140_dynamics.core.payload.diagram import check_point

    check = check_point(model, limits, mass, z, l)
    print(f"{NAME}: {check.sentence()}")
    return 0 if check.inside else 1


def _progress(z_size: int, l_size: int):
    """The rows of z done, shown as points (see ``tools.progress``), from now on."""
    from irb140_dynamics.tools.progress import Progress

    bar = Progress(NAME, "points")
    bar(0, z_size * l_size)
    return lambda done, total: bar(done * l_size, total * l_size)


def _workers(rows: int) -> int:
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:
        cores = os.cpu_count() or 1
    return max(1, min(cores, rows))


def _summary(diagram, written) -> str:
    import numpy as np

    from irb140_dynamics.core.errors import counted

    proven = [p.mass for p in diagram.points if p.proven]
    share = 100 * len(proven) / len(diagram.points)
    span = f", {min(proven):.3f} to {max(proven):.3f} kg" if proven else ""
    unproven = len(diagram.points) - len(proven)
    worst = ""
    if unproven:
        first = next(p for p in diagram.points if not p.proven)
        worst = f" (e.g. z {first.z:.3f} m, l {first.l:.3f} m: {first.reason})"
    return (
        f"{NAME}: {counted(len(diagram.points), 'point')} ({diagram.z.size} z x {diagram.l.size} l), "
        f"{len(proven)} proven ({share:.1f} %){span}; {unproven} unproven{worst}; "
        f"at z = l = 0: {np.round(diagram.masses()[0, 0], 3)} kg; wrote {', '.join(written)}"
    )


if __name__ == "__main__":
    from irb140_dynamics.entry import finish

    finish(main)
