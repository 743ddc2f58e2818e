"""load_diagram: the arm's load diagram, the largest payload per centre-of-mass position.

    irb140-load-diagram --out DIR [--params-file F | --urdf U [--base B] [--tip T]] [-p NAME:=VALUE]
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
(on a terminal, the rows done so far on stderr meanwhile).
Exit status 0; 1 with one line (a bad file, nothing written); 2 for a bad argument; 130
after Ctrl-C.
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m: the entry first, before the heavy imports
    from irb140_dynamics.entry import TOOL, start

    start("load_diagram", TOOL)

import math
import os
import sys

from irb140_dynamics.tools.cli import Parser, ToolError, check_model_paths, number, output_directory, run
from irb140_dynamics.tools.common import add_model_arguments, arm_of

NAME = "load_diagram"
MAX_POINTS = 20_000  # grid points: a diagram beyond this is a typo of --step
FILES = ("load_diagram.csv", "load_diagram.png")


def parser() -> Parser:
    p = Parser(prog=NAME, description=__doc__.split("\n\n")[0].split(": ", 1)[1])
    p.add_argument("--out", required=True, metavar="DIR", help="the folder to write the CSV and PNG into")
    add_model_arguments(p)
    p.add_argument("--z-max", type=number(0.0, 10.0), default=0.3, metavar="M", help="Z's last value [m] (0.3)")
    p.add_argument("--l-max", type=number(0.0, 10.0), default=0.2, metavar="M", help="L's last value [m] (0.2)")
    p.add_argument("--step", type=number(0.0, 10.0, above=True), default=0.01, metavar="M", help="grid step [m] (0.01)")
    p.add_argument(
        "--rated-mass",
        type=number(0.0, 1e6, above=True),
        default=6.0,
        metavar="KG",
        help="the rated payload: limits not given are derived from it; its curve is marked (6.0)",
    )
    return p


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
    args = parser().parse_args(argv)
    check_model_paths(args)
    out = output_directory(args.out)
    z, l = grid(args.z_max, args.step), grid(args.l_max, args.step)
    if z.size * l.size > MAX_POINTS:
        raise ToolError(
            f"--step {args.step:g}: {z.size} x {l.size} points, more than {MAX_POINTS:,}: give a larger step"
        )

    from irb140_dynamics.core.model.rigid_body import RigidBody
    from irb140_dynamics.core.payload import derive_torque_limits
    from irb140_dynamics.core.payload.diagram import load_diagram
    from irb140_dynamics.tools.load_diagram_plot import diagram_csv, diagram_png
    from irb140_dynamics.tools.outputs import Outputs

    source = arm_of(args)
    model, rated = source.model, RigidBody(args.rated_mass)
    limits = derive_torque_limits(model, rated)
    diagram = load_diagram(model, limits.values, z, l, _progress(z.size * l.size), _workers(z.size))
    csv, png = diagram_csv(diagram).encode(), diagram_png(diagram, rated.mass, os.path.basename(source.origin))
    with Outputs(interrupts) as outputs:
        outputs.directory(out, args.out)
        for name, data in zip(FILES, (csv, png)):
            outputs.stage(out / name, os.path.join(args.out, name), lambda stream, data=data: stream.write(data))
        written = outputs.commit()
    print(_summary(diagram, written))
    return 0


def _progress(points: int):
    """On a terminal: 'load_diagram: row 3 of 31 (651 points), 12 s' on stderr, redrawn."""
    if not sys.stderr.isatty():
        return None
    import time

    from irb140_dynamics.tools.cli import open_line

    started = time.monotonic()

    def show(done: int, total: int) -> None:
        sys.stderr.write(f"\r{NAME}: row {done} of {total} ({points} points), {time.monotonic() - started:.0f} s")
        open_line[0] = done < total
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show


def _workers(rows: int) -> int:
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:
        cores = os.cpu_count() or 1
    return max(1, min(cores, rows))


def _summary(diagram, written) -> str:
    import numpy as np

    proven = [p.mass for p in diagram.points if p.proven]
    share = 100 * len(proven) / len(diagram.points)
    span = f", {min(proven):.3f} to {max(proven):.3f} kg" if proven else ""
    unproven = len(diagram.points) - len(proven)
    worst = ""
    if unproven:
        first = next(p for p in diagram.points if not p.proven)
        worst = f" (e.g. z {first.z:.3f} m, l {first.l:.3f} m: {first.reason})"
    return (
        f"{NAME}: {len(diagram.points)} points ({diagram.z.size} z x {diagram.l.size} l), "
        f"{len(proven)} proven ({share:.1f} %){span}; {unproven} unproven{worst}; "
        f"at z = l = 0: {np.round(diagram.masses()[0, 0], 3)} kg; wrote {', '.join(written)}"
    )


if __name__ == "__main__":
    from irb140_dynamics.entry import finish

    finish(main)
