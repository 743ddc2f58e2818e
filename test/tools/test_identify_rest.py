"""identify on a recording as `record` leaves it: rest before the motion (from when the
recording started) and a long rest after it. It trims both, holds out the last 20 % of the
points that move (the last 20 % of the samples would be rest: nothing to validate on),
and says so in its report; the fit is as good as on the motion alone."""

import contextlib
import io
import re

import numpy as np
import pytest

from irb140_dynamics.core import irb140, rnea_batch
from irb140_dynamics.identification.excitation import optimise_excitation
from irb140_dynamics.tools import identify as identify_tool

from ..support.synthetic_arm import NOISE, QUANTUM, Samples, true_arm, write_csv

pytestmark = pytest.mark.slow  # the fixture simulates 25 s of an arm and identifies it

RATE, PERIOD, PERIODS = 250.0, 4.0, 3
BEFORE, AFTER = 5.0, 8.0  # s of rest: the last 20 % of the samples are all rest


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rest")
    arm = true_arm(3)
    trajectory = optimise_excitation(irb140(), PERIOD, 4, seed=2, iterations=0).trajectory
    motion = np.arange(int(PERIOD * PERIODS * RATE) + 1) / RATE
    Q, QD, QDD = trajectory.evaluate(motion)
    before, after = np.arange(int(BEFORE * RATE)), np.arange(int(AFTER * RATE))
    Q = np.vstack([np.repeat(Q[:1], len(before), 0), Q, np.repeat(Q[-1:], len(after), 0)])
    zeros = lambda k: np.zeros((k, 6))  # noqa: E731
    QD = np.vstack([zeros(len(before)), QD, zeros(len(after))])
    QDD = np.vstack([zeros(len(before)), QDD, zeros(len(after))])
    tau = rnea_batch(arm, Q, QD, QDD)
    noise = np.random.default_rng(5).normal(size=tau.shape) * NOISE * np.abs(tau).max(axis=0)
    t = np.arange(len(Q)) / RATE
    csv = write_csv(
        folder / "run.csv", Samples(t, np.round(Q / QUANTUM) * QUANTUM, QD, tau + noise, tau), arm.joint_names
    )
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        status = identify_tool.main([str(csv), "--out", str(folder / "identified.yaml"), "--quiet"])
    return status, printed.getvalue(), len(t) / RATE


def test_rest_is_trimmed_at_both_ends_and_said(run):
    status, printed, length = run
    assert status == 0, printed
    found = re.search(
        r"motion: ([\d.]+) s to ([\d.]+) s of ([\d.]+) s \(rest trimmed: ([\d.]+) s at the start, "
        r"([\d.]+) s at the end\)",
        printed,
    )
    assert found, printed
    start, end, span, rest_start, rest_end = map(float, found.groups())
    assert span == pytest.approx(length - 1 / RATE, abs=0.01)
    # the motion starts from rest (qd = 0): it moves from a moment after BEFORE on, and the
    # filter's half window (a few samples) may reach a little earlier
    assert BEFORE - 0.1 <= start <= BEFORE + 0.3 and start == rest_start
    assert AFTER - 0.1 <= rest_end <= AFTER + 0.3 and end == pytest.approx(span - rest_end)


def test_the_held_out_part_moves_and_the_fit_holds_on_it(run):
    status, printed, _ = run
    held = re.search(r"held out from ([\d.]+) s on: the last ([\d,]+) of ([\d,]+) moving fit points", printed)
    assert held, printed
    begins, count, total = float(held[1]), int(held[2].replace(",", "")), int(held[3].replace(",", ""))
    assert count == int(np.ceil(0.2 * total))
    assert BEFORE + 0.8 * PERIOD * PERIODS - 0.5 <= begins <= BEFORE + 0.8 * PERIOD * PERIODS + 0.5
    table = re.findall(r"^joint_\d +\S+ +\S+ +\((\S+) %\) +\S+ +\((\S+) %\)$", printed, flags=re.M)
    assert len(table) == 6 and all(float(identified) <= 2.0 < float(prior) for prior, identified in table), printed
