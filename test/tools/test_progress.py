"""tools.progress: a bar with the count and the time left on a terminal, a line per 10 %
elsewhere; and the long tools show it (load_diagram here, through a pipe and a pty)."""

from __future__ import annotations

import io
import os
import pty
import re
import select
import subprocess
import sys
import tty

import pytest

from irb140_dynamics.tools import progress as progress_module
from irb140_dynamics.tools.progress import Progress, duration

from ..support.paths import ROOT


class Clock:
    """Simulated time: the test says when each call happens."""

    def __init__(self):
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_durations_read_at_a_glance():
    assert [duration(s) for s in (0.4, 45, 59.6, 125, 3599, 3780)] == [
        "0 s",
        "45 s",
        "1 min 0 s",
        "2 min 5 s",
        "59 min 59 s",
        "1 h 3 min",
    ]


def test_not_on_a_terminal_one_line_per_tenth_with_the_time_left():
    stream, clock = io.StringIO(), Clock()
    bar = Progress("load_diagram", "points", stream, clock)
    for done in range(0, 651, 7):  # 2 s per 7 points: 651 points take 186 s
        bar(done, 651)
        clock.now += 2.0
    bar(651, 651)
    lines = stream.getvalue().splitlines()
    assert [line.split(":")[1].split("%")[0].strip() for line in lines] == [str(p) for p in range(10, 101, 10)]
    assert lines[0] == "load_diagram: 10 % (70/651 points), 2 min 46 s left"  # 581 points to go at 2/7 s each
    assert lines[4] == "load_diagram: 50 % (329/651 points), 1 min 32 s left"
    assert lines[-1] == "load_diagram: 100 % (651/651 points), done in 3 min 6 s"
    assert "\r" not in stream.getvalue()


def test_a_jump_over_several_tenths_is_one_line_and_nothing_after_the_end():
    stream, clock = io.StringIO(), Clock()
    bar = Progress("excitation: optimising", "iterations", stream, clock)
    bar(0, 40)
    clock.now += 30.0
    bar(15, 40)  # 37.5 %: one line, at 30 %
    clock.now += 10.0
    bar(40, 40)
    bar(40, 40)
    assert stream.getvalue().splitlines() == [
        "excitation: optimising: 30 % (15/40 iterations), 50 s left",
        "excitation: optimising: 100 % (40/40 iterations), done in 40 s",
    ]


def test_on_a_terminal_a_bar_redrawn_in_place_at_most_five_times_a_second():
    master, slave = pty.openpty()
    tty.setraw(slave)  # the text as written (no "\n" -> "\r\n")
    try:
        stream, clock = os.fdopen(slave, "w", closefd=False), Clock()
        bar = Progress("identify: reading run.mcap", "samples", stream, clock)
        assert bar.terminal
        for done in range(0, 1001, 100):  # every 0.125 s: only every other one is drawn
            bar(done, 1000)
            clock.now += 0.125
        stream.close()
        text = b""
        while select.select([master], [], [], 0)[0]:  # what was written is there: read it all
            text += os.read(master, 65536)
        text = text.decode()
    finally:
        os.close(master)
        os.close(slave)
    frames = text.split("\r")[1:]
    assert len(frames) == 6, frames  # 0, 200, ..., 800 and the last (always drawn)
    assert frames[0] == f"identify: reading run.mcap: [{' ' * 30}]   0 % 0/1,000 samples, time left not known yet\x1b[K"
    assert frames[2] == f"identify: reading run.mcap: [{'#' * 12}{' ' * 18}]  40 % 400/1,000 samples, 1 s left\x1b[K"
    assert frames[-1].startswith(f"identify: reading run.mcap: [{'#' * 30}] 100 % 1,000/1,000 samples, done in 1 s")
    assert frames[-1].endswith("\n") and text.count("\n") == 1


def test_an_unfinished_bar_on_stderr_is_ended_before_an_error_line(monkeypatch, capsys):
    from irb140_dynamics.tools.cli import _say

    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    Progress("load_diagram", "points")(3, 10)
    assert progress_module.open_line[0]
    _say("load_diagram: interrupted")
    err = capsys.readouterr().err
    assert err.endswith("\x1b[K\nload_diagram: interrupted\n") and not progress_module.open_line[0]


DIAGRAM = ["--z-max", "0.1", "--l-max", "0.05", "--step", "0.05"]  # 3 rows of 2 points


def _tool_environment() -> dict:
    return {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}


@pytest.mark.slow
def test_load_diagram_through_a_pipe_says_a_line_per_tenth(tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "irb140_dynamics.tools.load_diagram", "--out", str(tmp_path), *DIAGRAM],
        capture_output=True,
        text=True,
        env=_tool_environment(),
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert [re.sub(r", .*", "", line) for line in lines] == [
        "load_diagram: 30 % (2/6 points)",
        "load_diagram: 60 % (4/6 points)",
        "load_diagram: 100 % (6/6 points)",
    ], done.stderr
    assert lines[0].endswith(" left") and "done in" in lines[-1]
    assert done.stdout.startswith("load_diagram: 6 points") and "\r" not in done.stderr


@pytest.mark.slow
def test_load_diagram_on_a_terminal_draws_its_bar(tmp_path):
    master, slave = pty.openpty()
    tty.setraw(slave)
    try:
        process = subprocess.Popen(
            [sys.executable, "-m", "irb140_dynamics.tools.load_diagram", "--out", str(tmp_path), *DIAGRAM],
            stdout=subprocess.PIPE,
            stderr=slave,
            env=_tool_environment(),
        )
        os.close(slave)
        seen = b""
        while True:
            try:
                chunk = os.read(master, 4096)
            except OSError:  # the pty's other end closed: the tool has exited
                break
            if not chunk:
                break
            seen += chunk
        out, _ = process.communicate(timeout=300)
    finally:
        os.close(master)
    text = seen.decode()
    assert process.returncode == 0, text
    frames = text.split("\r")[1:]
    assert frames[0].startswith(f"load_diagram: [{' ' * 30}]   0 % 0/6 points, time left not known yet"), text
    assert re.search(r"load_diagram: \[#{30}\] 100 % 6/6 points, done in \d+ s", frames[-1]), text
    assert out.decode().startswith("load_diagram: 6 points")


def test_retime_on_a_long_input_says_its_steps(monkeypatch, capsys, tmp_path):
    """From LONG_INPUT bytes on (here lowered to the example's size), a line per step; below, none."""
    from irb140_dynamics.tools import retime

    example = ROOT / "docs" / "trajectory_example.yaml"
    arguments = ["--params-file", str(ROOT / "config" / "irb140.yaml"), str(example), str(tmp_path / "out.yaml")]
    assert retime.main(arguments) == 0
    assert capsys.readouterr().err == ""  # a short input: done in a moment, nothing said
    monkeypatch.setattr(retime, "LONG_INPUT", example.stat().st_size)
    assert retime.main(arguments) == 0
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(" (")[0] for line in lines] == [
        "retime: checking the input: 20 %",
        "retime: re-timing: 40 %",
        "retime: checking the result: 60 %",
        "retime: writing: 80 %",
        "retime: 100 %",
    ], lines
    assert lines[-1].startswith("retime: 100 % (5/5 steps), done in ")
