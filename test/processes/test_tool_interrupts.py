"""Ctrl-C (or SIGTERM) at any moment of identify, excitation and export_urdf, as processes: one line
('<tool>: interrupted'), no traceback, exit 130 (143), and no output left behind (no
result, no plot, no temporary file, no folder made for them); or, when the signal came
after the tool finished its work, exit 0 with every output whole. Seeded moments from
the tool's start (its handlers installed) to past its end. Relative paths are the
caller's: the tools run in their own working folder."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from irb140_dynamics.core import irb140, rnea_batch
from irb140_dynamics.identification.excitation import optimise_excitation

from ..support.common import spread
from ..support.node_process import TIMEOUT, handles_sigterm
from ..support.paths import ROOT
from ..support.synthetic_arm import Samples, true_arm, write_csv


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    folder = tmp_path_factory.mktemp("recording")
    trajectory = optimise_excitation(irb140(), 3.0, 3, seed=1, iterations=0).trajectory
    t = np.arange(int(6 * 200)) / 200.0
    Q, QD, QDD = trajectory.evaluate(t)
    tau = rnea_batch(true_arm(1), Q, QD, QDD)
    return write_csv(folder / "run.csv", Samples(t, Q, QD, tau, tau), irb140().joint_names)


def moments(seed: int, longest: float, count: int = 12) -> list:
    """``count`` seeded (delay, signals) cases, delays up to ``longest`` s; in the suite the
    earliest, a middle and the latest of them (support.common.spread)."""
    rng = np.random.default_rng(seed)
    cases = []
    for k in range(count):
        signals = [int(rng.choice([signal.SIGINT, signal.SIGTERM])) for _ in range(int(rng.integers(1, 4)))]
        cases.append(pytest.param(float(rng.uniform(0.0, longest)), signals, id=f"case{k}"))
    return spread(cases, 3, key=lambda case: case.values[0])


def stop_codes(signals) -> set[int]:
    """The exit statuses a run stopped by ``signals`` may end with: 128 + the first signal
    taken. Signals sent 10 ms apart to a process that was not scheduled meanwhile are
    pending together, and Python takes pending signals in the order of their numbers, not
    of their sending: any of them may be the first taken."""
    return {128 + s for s in signals}


def interrupted(command, folder, delay, signals):
    environment = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1"}
    process = subprocess.Popen(
        command, cwd=folder, env=environment, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    try:
        deadline = time.monotonic() + TIMEOUT
        while not handles_sigterm(process.pid):
            assert time.monotonic() < deadline and process.poll() is None
            time.sleep(0.005)
        time.sleep(delay)
        for s in signals:
            if process.poll() is None:
                process.send_signal(s)
            time.sleep(0.01)
        output, _ = process.communicate(timeout=4 * TIMEOUT)
    finally:
        process.kill()
    return process.returncode, output


@pytest.mark.slow
@pytest.mark.parametrize("delay, signals", moments(7, 8.0))
def test_identify_interrupted_at_any_moment(recording, tmp_path, delay, signals):
    (tmp_path / "run.csv").write_bytes(recording.read_bytes())
    command = [
        sys.executable,
        "-m",
        "irb140_dynamics.tools.identify",
        "run.csv",
        "--out",
        "out/identified.yaml",
        "--plots",
        "out/plots",
    ]
    (tmp_path / "out").mkdir()
    code, output = interrupted(command, tmp_path, delay, signals)
    assert "Traceback" not in output, output
    left = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*"))
    if code == 0:  # it had finished its work: everything there, whole
        assert "wrote out/identified.yaml" in output and "wrote out/plots/residuals.png" in output, output
        assert left == [
            "out",
            "out/identified.yaml",
            "out/plots",
            "out/plots/residuals.png",
            "out/plots/torques.png",
            "run.csv",
        ], left
        return
    assert code in stop_codes(signals), output
    assert output.count("identify: interrupted") == 1 and "error" not in output, output
    assert left == ["out", "run.csv"], left


@pytest.mark.slow
@pytest.mark.parametrize("delay, signals", moments(8, 3.0))
def test_excitation_interrupted_at_any_moment(tmp_path, delay, signals):
    command = [
        sys.executable,
        "-m",
        "irb140_dynamics.tools.excitation",
        "--out",
        "excitation.yaml",
        "--iterations",
        "2",
        "--period",
        "3",
    ]
    code, output = interrupted(command, tmp_path, delay, signals)
    assert "Traceback" not in output, output
    left = sorted(p.name for p in tmp_path.iterdir())
    if code == 0:
        assert left == ["excitation.yaml"] and "wrote excitation.yaml" in output, output
        return
    assert code in stop_codes(signals) and output.count("excitation: interrupted") == 1, output
    assert left == [], left


@pytest.mark.slow
@pytest.mark.parametrize("delay, signals", moments(9, 3.0))
def test_export_urdf_interrupted_at_any_moment(tmp_path, delay, signals):
    command = [sys.executable, "-m", "irb140_dynamics.tools.export_urdf", "--out", "arm.urdf"]
    code, output = interrupted(command, tmp_path, delay, signals)
    assert "Traceback" not in output, output
    left = sorted(p.name for p in tmp_path.iterdir())
    if code == 0:
        assert left == ["arm.urdf"] and "wrote arm.urdf" in output, output
        return
    assert code in stop_codes(signals) and output.count("export_urdf: interrupted") == 1, output
    assert left == [], left
