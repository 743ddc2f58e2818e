"""A verdict is proven or says it is not: OK and OVER-LIMIT only from a
finished computation (a bound within the limit; a real torque over it), UNPROVEN with the
best bound and the reason where a proof ran out of budget or the analysis out of time; a
cancelled analysis stops at its next check. The chains here are beyond the harmonic proofs
(more than 9 joints: plain interval bounds, their budget spent) or slow to analyse (30)."""

import threading
from dataclasses import replace

import numpy as np
import pytest

from irb140_dynamics.core import RigidBody, gravity, gravity_batch, irb140
from irb140_dynamics.core.payload import check_payload, derive_torque_limits, stop, workspace_load
from irb140_dynamics.core.payload.stop import Cancelled, stopping
from irb140_dynamics.core.payload.workspace import JointRanges

from ..support.chains import chain

PAYLOAD = RigidBody(3.0)
WAIT = 120.0  # s: for a worker thread to end, on a loaded 2-core machine


@pytest.fixture(scope="module")
def twelve():
    """A 12-joint chain, its derived limits and the payload's workspace load."""
    model = chain(12)
    limits = derive_torque_limits(model)
    return model, limits, workspace_load(model, PAYLOAD, limits)


def test_a_payload_that_fits_where_searched_but_not_proven_is_unproven_not_over(twelve):
    """The reported case: a long chain whose payload fits was called OVER-LIMIT because its
    bounds (plain intervals, budget spent) were taken for torques."""
    model, limits, load = twelve
    check = check_payload(model, PAYLOAD, limits, workspace=load)
    assert check.verdict == "UNPROVEN" and not check.ok and check.over == []
    assert np.all(np.abs(load.torque) <= np.array(limits.values) * (1 + 1e-9))  # fits where searched
    assert np.all(load.bound > np.abs(load.torque))  # but the bounds are far off: the budget ran out
    carrying = model.with_payload(PAYLOAD)
    for j in range(model.n):  # each torque found is a real one, at its pose
        assert gravity(carrying, load.pose[j])[j] == pytest.approx(load.torque[j], rel=1e-9, abs=1e-9)
    headline = check.report().splitlines()[0]
    assert headline == check.headline()
    assert headline.startswith("UNPROVEN: 3.000 kg not proven to fit: joint_")
    assert "worst static torque is proven only up to" in headline
    assert headline.endswith(
        "the proof's budget ran out (plain interval bounds: more than 9 joints); 11 more joints unproven"
    )


def test_the_bounds_of_a_long_chain_are_bounds(twelve):
    model, _, load = twelve
    ranges = JointRanges.of(model)
    rng = np.random.default_rng(23)
    Q = ranges.lower + rng.random((20_000, model.n)) * (ranges.upper - ranges.lower)
    dense = np.abs(gravity_batch(model.with_payload(PAYLOAD), Q))
    assert np.all(dense.max(axis=0) <= load.bound)


@pytest.mark.parametrize("case", ["far above the bounds", "below a torque found", "between"])
def test_given_limits_give_each_verdict_where_the_proof_allows(twelve, case):
    """Given limits on the same chain: above every bound OK, below a torque found at a real
    pose OVER-LIMIT, between the two UNPROVEN."""
    _, _, load = twelve
    torque, bound = np.abs(load.torque), load.bound
    high = 2 * bound.max()
    given = {
        "far above the bounds": np.full(12, high),
        "below a torque found": np.where(np.arange(12) == 1, 0.9 * torque[1], high),
        "between": np.where(np.arange(12) == 1, 0.5 * (torque[1] + bound[1]), high),
    }[case]
    model = chain(12)
    model = replace(model, joints=tuple(replace(j, torque_limit=float(L)) for j, L in zip(model.joints, given)))
    check = check_payload(model, PAYLOAD, derive_torque_limits(model), workspace=load)
    expected = {"far above the bounds": "OK", "below a torque found": "OVER-LIMIT", "between": "UNPROVEN"}[case]
    assert check.verdict == expected and check.ok == (expected == "OK")
    headline = check.headline()
    if expected == "OVER-LIMIT":
        assert check.over == ["joint_2"]
        assert headline.startswith(f"OVER-LIMIT: 3.000 kg does not fit: joint_2 needs {torque[1]:.3f} N m at (")
        assert headline.endswith(f"111.1 % of its {given[1]:.3f} N m limit")
    elif expected == "UNPROVEN":
        assert check.unproven == ["joint_2"]
        assert headline.startswith(
            f"UNPROVEN: 3.000 kg not proven to fit: joint_2's worst static torque is proven "
            f"only up to {bound[1]:.3f} N m"
        )
    else:
        worst = int(np.argmax(bound / given))
        assert (
            headline
            == f"OK: 3.000 kg fits, worst joint_{worst + 1} at {100 * bound[worst] / given[worst]:.1f} % of its limit"
        )


def test_an_analysis_out_of_time_is_unproven_and_says_so():
    """No time at all: the search keeps its samples, each proof its first bound; the limits
    and the workspace load say they were cut, and nothing cut is remembered."""
    model, payload = irb140(), RigidBody(2.0, (0.0, 0.0, 0.12))  # a shape of its own
    with stopping(seconds=0.0) as deadline:
        limits = derive_torque_limits(model, RigidBody(6.0, (0.0, 0.0, 0.001)))  # a rated payload of its own
        load = workspace_load(model, payload, limits)
    assert deadline.ran_out and limits.out_of_time and load.out_of_time
    check = check_payload(model, payload, limits, workspace=load)
    assert check.verdict == "UNPROVEN" and check.over == []
    assert check.headline().startswith("UNPROVEN: 2.000 kg not proven to fit: ")
    assert ": the analysis ran out of time" in check.headline()
    full = workspace_load(model, payload, limits)  # the same again with time: proven, not the cut one
    assert not full.out_of_time and np.all(full.gap < 1e-3 * np.abs(full.torque).max())
    assert np.all(np.abs(full.torque) >= np.abs(load.torque) - 1e-9)  # the search went on from the same samples


def test_a_slow_chain_out_of_time_answers_with_its_bounds():
    """30 joints, no time: still an answer, UNPROVEN, its torques real ones."""
    model = chain(30)
    with stopping(seconds=0.0):
        check = check_payload(model, PAYLOAD)
    assert check.verdict == "UNPROVEN" and "the analysis ran out of time" in check.headline()
    j = 1
    carrying = model.with_payload(PAYLOAD)
    assert gravity(carrying, check.workspace.pose[j])[j] == pytest.approx(check.workspace.torque[j], rel=1e-9)


def test_a_cancelled_analysis_stops_at_its_next_check(monkeypatch):
    """The analysis of a 30-joint chain (the search alone takes tens of seconds) cancelled
    from another thread: it raises Cancelled at the first check after the cancel."""
    cancel, started, survived, outcome = threading.Event(), threading.Event(), [], []
    real = stop.Stop.out_of_time

    def counting(self):
        cancelled = cancel.is_set()
        started.set()
        result = real(self)  # raises once cancelled
        if cancelled:
            survived.append(True)
        return result

    monkeypatch.setattr(stop.Stop, "out_of_time", counting)

    def analyse():
        try:
            with stopping(cancel):
                derive_torque_limits(chain(30))
            outcome.append("finished")
        except Cancelled:
            outcome.append("cancelled")

    worker = threading.Thread(target=analyse, daemon=True)
    worker.start()
    assert started.wait(WAIT)
    cancel.set()
    worker.join(WAIT)
    assert not worker.is_alive() and outcome == ["cancelled"] and survived == []


def test_nothing_stops_outside_a_stopping():
    assert stop.out_of_time() is False and stop.current_stop() is None
    with stopping(seconds=1e9) as outer, stopping(seconds=0.0) as inner:
        assert stop.out_of_time() and inner.ran_out and not outer.ran_out
    with pytest.raises(ValueError, match="seconds: must be >= 0"), stopping(seconds=float("nan")):
        pass


def test_the_ur5_with_a_2_kg_tool_gives_its_max_payload_without_a_numpy_warning():
    """Where the bounds barely change between two masses, the division that mixes them may
    overflow to inf in a joint it does not select: no RuntimeWarning reaches the node's log."""
    import warnings

    from irb140_dynamics.core.urdf import load_urdf

    from ..support.paths import URDF_DATA

    model = load_urdf((URDF_DATA / "ur5.urdf").read_text(), "base_link", "tool0").model
    tool = RigidBody(2.0, (0.04, -0.03, 0.06))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        best = workspace_load(model, tool, derive_torque_limits(model)).max_payload
    assert best.mass > 0 and np.isfinite(best.mass)
