"""scripts/run.sh as a user types it, from a directory of their own:
--help, relative paths from the caller's directory, a node that fails stops the rest and is
named, Ctrl-C stops everything with exit 0, the demo's plot where it says."""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

from ..support.node_process import communicate
from ..support.paths import ROOT

RUN = ROOT / "scripts" / "run.sh"
BUILD_AND_START = 300.0  # s: colcon build and the nodes' start on a loaded 2-core machine


def run_script(*arguments: str, cwd: Path) -> subprocess.Popen:
    environment = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    return subprocess.Popen(
        [str(RUN), *arguments],
        cwd=cwd,
        env=environment,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )


def left_behind(process: subprocess.Popen) -> list[str]:
    """The processes still alive in run.sh's session (it started them: nodes it left behind)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if os.getsid(int(entry.name)) == process.pid:
                    found.append((entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace"))
            except OSError:
                continue
    return found


def kill_session(process: subprocess.Popen) -> None:
    """SIGKILL to run.sh and everything in its session (its nodes are in process groups of
    their own): a failed test leaves nothing running."""
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if os.getsid(int(entry.name)) == process.pid:
                    os.kill(int(entry.name), signal.SIGKILL)
            except OSError:
                continue
    process.wait(timeout=30)


def test_help_is_usage_and_exit_0(tmp_path):
    done = subprocess.run([str(RUN), "--help"], cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and "Traceback" not in done.stdout + done.stderr, done
    assert done.stdout.startswith("usage: scripts/run.sh") and "--demo" in done.stdout, done.stdout
    assert subprocess.run([str(RUN), "-h"], cwd=tmp_path, capture_output=True, timeout=60).returncode == 0


def test_a_missing_params_file_is_named_from_the_callers_directory(tmp_path):
    process = run_script("--demo", "--params-file", "missing.yaml", cwd=tmp_path)
    output, _ = process.communicate(timeout=60)
    assert process.returncode == 2, output
    assert output.strip() == f"run.sh: --params-file missing.yaml: no such file (looked for {tmp_path}/missing.yaml)"


@pytest.mark.slow
def test_a_node_that_cannot_start_stops_the_others_and_is_named(tmp_path):
    (tmp_path / "negative.yaml").write_text("/**:\n  ros__parameters:\n    payload:\n      mass: -3.0\n")
    process = run_script("--params-file", "negative.yaml", cwd=tmp_path)  # relative: from tmp_path
    try:
        output, _ = process.communicate(timeout=BUILD_AND_START)
    finally:
        leftovers = left_behind(process)
        kill_session(process)
    assert process.returncode == 1, output
    assert f"{tmp_path}/negative.yaml" in output and "payload.mass: must be between 0 and 1e+06, got -3.0" in output
    assert "stopped by itself; stopping the others" in output, output
    assert "interrupted" not in output.lower().replace("interrupted (ctrl-c) before the node was ready", ""), output
    assert leftovers == [], output


@pytest.mark.slow
def test_the_demo_stops_on_ctrl_c_and_writes_its_plot_where_it_says(tmp_path):
    process = run_script("--demo", cwd=tmp_path)
    lines: list[str] = []
    try:
        deadline = time.monotonic() + BUILD_AND_START
        for line in process.stdout:
            lines.append(line)
            if line.startswith("t=") and "joint_1" in line and "mrad" in line:
                break
            assert time.monotonic() < deadline, "".join(lines)
        os.kill(process.pid, signal.SIGINT)  # Ctrl-C: the terminal sends it to run.sh
        rest, _ = communicate(process, 120)
    finally:
        leftovers = left_behind(process)
        kill_session(process)
    output = "".join(lines) + rest
    assert process.returncode == 0 and "Traceback" not in output, output
    plot = tmp_path / "demo_tracking.png"
    assert f"plot written: {plot}" in output and plot.stat().st_size > 0, output
    assert "tracking error RMS over the last second, per joint [mrad] (id_node on the built-in IRB-140" in output
    assert leftovers == [], output


@pytest.mark.slow
def test_the_demo_with_a_duration_ends_by_itself_with_its_plot(tmp_path):
    """--duration S: S seconds of tracking figures, the first from a held arm, then the plot,
    every node stopped, exit 0."""
    seconds = 1
    process = run_script("--demo", "--duration", str(seconds), cwd=tmp_path)
    try:
        output, _ = communicate(process, BUILD_AND_START + 120)
    finally:
        leftovers = left_behind(process)
        kill_session(process)
    assert process.returncode == 0 and "Traceback" not in output, output
    plot = tmp_path / "demo_tracking.png"
    assert f"plot written: {plot}" in output and plot.stat().st_size > 0, output
    assert f"run.sh: the demo's {seconds} s are over; stopping the nodes" in output, output
    figures = [line for line in output.splitlines() if line.startswith("t=") and "mrad" in line]
    assert figures, output  # the loop ran: its figures came before the end
    first = figures[0].split()
    joint_2 = float(first[first.index("joint_2") + 1])
    assert joint_2 < 200.0, figures[0]  # from a held arm: sim_node waited on its brakes (a fall: some 850 mrad)
    assert "stopped by itself" not in output and leftovers == [], output


def test_a_duration_needs_the_demo_and_a_positive_number(tmp_path):
    for arguments, message in (
        (["--duration", "5"], "run.sh: --duration is for --demo (the nodes alone run until Ctrl-C)"),
        (["--demo", "--duration", "0"], "run.sh: --duration needs a number of seconds > 0, e.g. --duration 30"),
        (["--demo", "--duration", "soon"], "run.sh: --duration needs a number of seconds > 0, e.g. --duration 30"),
        (["--demo", "--duration"], "run.sh: --duration needs a number of seconds > 0, e.g. --duration 30"),
    ):
        done = subprocess.run([str(RUN), *arguments], cwd=tmp_path, capture_output=True, text=True, timeout=60)
        assert (done.returncode, done.stdout, done.stderr.strip()) == (2, "", message), (arguments, done)
