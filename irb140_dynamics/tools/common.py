"""What the command-line tools share: the prior model, errors in one line, a progress bar."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from irb140_dynamics.core.io.params_file import load_model
from irb140_dynamics.core.model.robot_model import RobotModel
from irb140_dynamics.package_files import default_config_path


class ToolError(Exception):
    """An error the tool reports in one line (exit status 1)."""


def prior_model(params_file: str | None) -> tuple[RobotModel, Path]:
    """The model of ``params_file`` (its ``/**`` section), by default the package's IRB-140."""
    path = Path(params_file) if params_file else default_config_path()
    if not path.is_file():
        raise ToolError(f"{path}: no such parameter file")
    try:
        return load_model(path), path
    except (ValueError, OSError) as error:  # ModelError, YAML errors are ValueErrors
        raise ToolError(f"{path}: {error}") from None


def run(tool: str, body) -> int:
    """body() -> exit status; a ToolError or bad input becomes 'tool: error: ...' and status 1."""
    try:
        return body()
    except (ToolError, ValueError, OSError) as error:
        print(f"{tool}: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{tool}: interrupted", file=sys.stderr)
        return 130


class ProgressBar:
    """'reading FILE: [#####     ] 52 % 1,234/2,345 samples, 3 s' on stderr, redrawn at most 5 times a second."""

    WIDTH = 30

    def __init__(self, stream=None, interval: float = 0.2):
        self.stream = stream or sys.stderr
        self.interval = interval
        self.start = time.monotonic()
        self.last = -1e9

    def __call__(self, path: str, done: int, total: int) -> None:
        now = time.monotonic()
        if done == 0:
            self.start = now
        finished = total > 0 and done >= total
        if not finished and now - self.last < self.interval:
            return
        self.last = now
        fraction = min(done / total, 1.0) if total > 0 else 0.0
        bar = "#" * int(self.WIDTH * fraction)
        self.stream.write(
            f"\rreading {Path(path).name}: [{bar:<{self.WIDTH}}] {100 * fraction:3.0f} % "
            f"{done:,}/{total:,} samples, {now - self.start:.0f} s"
        )
        if finished:
            self.stream.write("\n")
        self.stream.flush()
