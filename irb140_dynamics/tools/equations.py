"""equations: the equations of motion in closed form, as LaTeX, SymPy, C99 or NumPy Python.

    equations --form c --out gen/                      (the package's IRB-140)
    equations [--params-file F] [--urdf arm.urdf [--base LINK --tip LINK]] [-p NAME:=VALUE] --form FORM --out DIR
              [--what tau,M,C,g,regressor,dtau,qdd,dqdd,Minv] [--symbolic-parameters] [--payload-mass KG]
              [--prefix NAME]

The model is read as every tool and node reads it (``core.io.arm_source``): the package's
IRB-140, the params file's ``/**`` section over it, then -p; or the URDF's chain.

Derived by running the package's own recursions on symbols (irb140_dynamics.core.equations).
FORM: latex, sympy, c or python. --what defaults to tau,M,C,g (C: the torques C(q, qd) qd);
dtau, qdd, dqdd and Minv (the derivatives, the forward dynamics, M^-1) are written in the C
form of a model with numbers. --out may exist: the tool's files in it are replaced, nothing
else is touched; on any error nothing is written there (and no folder made).
"""

from __future__ import annotations

if __name__ == "__main__":  # python -m: the entry first, before the heavy imports
    from irb140_dynamics.entry import TOOL, start

    start("equations", TOOL)

import argparse
import os
import re
import sys
import threading
import time
from dataclasses import replace
from pathlib import Path

from ..core import RigidBody
from ..core.equations import DEFAULT_QUANTITIES, FORMS, QUANTITIES, file_names, generate
from ..core.errors import one_line
from ..package_files import default_config_path
from .cli import ToolError, check_model_paths, files_in, output_directory, refuse_input_as_output, run
from .common import add_model_arguments, model_inputs
from .common import arm_of as _arm_of
from .outputs import Outputs

NAME = "equations"
QUIET_SECONDS = 2.0  # a progress line on stderr once the work takes longer than this


class _ArgumentParser(argparse.ArgumentParser):
    def error(self, message):
        raise ToolError(message)


def parser() -> argparse.ArgumentParser:
    parser = _ArgumentParser(prog=NAME, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_model_arguments(parser, "the model (default: the package's IRB-140)")
    parser.add_argument("--form", required=True, help=f"one of {', '.join(FORMS)}")
    parser.add_argument("--out", required=True, help="the folder to write into")
    parser.add_argument("--what", default=",".join(DEFAULT_QUANTITIES), help=f"of {','.join(QUANTITIES)}")
    parser.add_argument(
        "--symbolic-parameters",
        action="store_true",
        help="masses, first moments, inertias, friction, armature and payload as named symbols",
    )
    parser.add_argument(
        "--payload-mass", type=float, help="kg: a point mass at the flange origin, replacing the model's payload"
    )
    parser.add_argument("--prefix", help="name of the C functions and the files (default: the input file's stem)")
    return parser


def main(argv: list[str] | None = None) -> int:
    return run(NAME, lambda interrupts: _main(sys.argv[1:] if argv is None else argv, interrupts))


def _main(argv: list[str], interrupts) -> int:
    args = parser().parse_args(argv)
    if args.form not in FORMS:
        raise ToolError(f"unknown form {args.form!r}: choose from {', '.join(FORMS)}")
    what = tuple(w.strip() for w in args.what.split(",") if w.strip())
    unknown = [w for w in what if w not in QUANTITIES]
    if unknown or not what:
        raise ToolError(
            f"unknown quantity {unknown[0] if unknown else args.what!r}: choose from {','.join(QUANTITIES)}"
        )
    check_model_paths(args)
    model = arm_of(args).model
    path = Path(args.urdf or args.params_file or default_config_path())
    prefix = args.prefix or _identifier(path.stem)
    if not prefix.isidentifier() or not prefix.isascii():
        raise ToolError(f"--prefix {prefix!r} is not a C identifier")
    out = output_directory(args.out)  # checked before any work, made only with the files
    refuse_input_as_output(model_inputs(args), files_in(out, args.out, file_names((args.form,), prefix)))
    with _Progress() as progress:
        files = generate(model, (args.form,), what, args.symbolic_parameters, prefix, path.name, progress)
    with Outputs(interrupts) as outputs:  # all or none; no folder left behind
        outputs.directory(out, args.out)
        for name, text in files.items():
            outputs.text(out / name, os.path.normpath(os.path.join(args.out, name)), text)
        for typed in outputs.commit():
            print(typed)
    return 0


def arm_of(args: argparse.Namespace):
    """The arm of the arguments (``common.arm_of``, as every tool reads it), with
    --payload-mass at the flange origin, replacing the model's payload, when given."""
    arm = _arm_of(args)
    if args.payload_mass is None:
        return arm
    try:
        return replace(arm, model=arm.model.with_payload(RigidBody(args.payload_mass)))
    except ValueError as error:
        raise ToolError(f"--payload-mass: {one_line(error)}") from None


def _identifier(stem: str) -> str:
    name = re.sub(r"\W", "_", stem.lower())
    return name if name[:1].isalpha() else f"robot_{name}"


class _Progress:
    """stage(text): noted; once the work has taken QUIET_SECONDS, each stage and the time
    are shown on stderr (redrawn in place on a terminal, a line per stage otherwise)."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.stage, self.last = "starting", None
        self.start = time.monotonic()
        self.shown = False
        self._lock = threading.Lock()
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._show, daemon=True)

    def __call__(self, stage: str) -> None:
        with self._lock:
            self.stage = stage
            if self.shown:
                self._draw()

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *_exception):
        self._done.set()
        self._thread.join()
        if self.shown:
            line = f"{NAME}: done in {time.monotonic() - self.start:.0f} s"
            self.stream.write(f"\r{line}\033[K\n" if self.tty else f"{line}\n")
            self.stream.flush()

    def _show(self):
        if self._done.wait(QUIET_SECONDS):
            return
        while True:
            with self._lock:
                if self._done.is_set():
                    return
                self.shown = True
                self._draw()
            if self._done.wait(1.0):
                return

    def _draw(self):
        elapsed = time.monotonic() - self.start
        if self.tty:
            self.stream.write(f"\r{NAME}: {self.stage}, {elapsed:.0f} s\033[K")
        elif self.stage != self.last:
            self.stream.write(f"{NAME}: {self.stage} ({elapsed:.0f} s)\n")
        self.last = self.stage
        self.stream.flush()


if __name__ == "__main__":
    from irb140_dynamics.entry import finish

    finish(main)
