"""The controller's interpolation, against SciPy's piecewise polynomials matched to the same
derivatives (BPoly.from_derivatives), segment by segment."""

import numpy as np
import pytest
from scipy.interpolate import BPoly

from irb140_dynamics.core.trajectories import Trajectory, TrajectoryError
from irb140_dynamics.core.trajectories.interpolation import spline

NAMES = ("a", "b", "c")


def _random(rng, points=6, velocities=True, accelerations=True, t0=0.0):
    t = t0 + np.cumsum(rng.uniform(0.1, 0.7, points))
    q, qd, qdd = rng.normal(size=(3, points, 3))
    return Trajectory.of(NAMES, t, q, qd if velocities else None, qdd if accelerations else None)


def _reference(tr, k, derivatives, t):
    """The polynomial of segment k (points k, k+1) matched to ``derivatives`` orders, at t."""
    out = []
    for j in range(tr.n):
        ends = [[tr.q[i, j], tr.qd[i, j], tr.qdd[i, j]][: derivatives + 1] for i in (k, k + 1)]
        poly = BPoly.from_derivatives(tr.t[k : k + 2], ends)
        out.append([poly(t), poly.derivative(1)(t), poly.derivative(2)(t)])
    return np.moveaxis(np.array(out), 0, -1)  # (3, len(t), n)


@pytest.mark.parametrize(
    ("velocities", "accelerations", "derivatives"), [(True, True, 2), (True, False, 1), (False, False, 0)]
)
def test_segments_match_the_polynomial_of_their_degree(velocities, accelerations, derivatives):
    rng = np.random.default_rng(1)
    tr = _random(rng, velocities=velocities, accelerations=accelerations)
    sp = spline(tr)
    assert (sp.degree == [5, 3, 1][2 - derivatives]).all()
    for k in range(len(tr.t) - 1):
        t = np.linspace(tr.t[k], tr.t[k + 1], 7)[:-1]
        ours = np.array(sp.evaluate(t, np.full(len(t), k + 1)))  # segment 0 runs up to the first point
        expected = _reference(tr, k, derivatives, t)
        if derivatives == 0:
            expected[2] = 0.0  # the controller outputs no acceleration on a linear segment
        np.testing.assert_allclose(ours, expected, atol=1e-9 * (1 + np.abs(expected).max()))


def test_the_degree_is_the_lower_of_two_points():
    rng = np.random.default_rng(2)
    tr = _random(rng, points=4)
    has_qdd = tr.has_qdd.copy()
    has_qdd[2] = False
    mixed = Trajectory(tr.joint_names, tr.t, tr.q, tr.qd, tr.qdd, tr.has_qd, has_qdd)
    assert spline(mixed).degree.tolist() == [5, 5, 3, 3]  # before point 0, then segments 0-1, 1-2, 2-3


def test_before_the_first_point_it_moves_from_the_start_state():
    rng = np.random.default_rng(3)
    tr = _random(rng, t0=1.0)
    start = (rng.normal(size=3), np.zeros(3), np.zeros(3))
    sp = spline(tr, start)
    assert sp.point[0] == -1 and sp.t0[0] == 0.0
    q, qd, qdd = sp.evaluate(np.array([0.0, tr.t[0]]), np.array([0, 0]))
    np.testing.assert_allclose(q, [start[0], tr.q[0]], atol=1e-12)
    np.testing.assert_allclose(qd, [np.zeros(3), tr.qd[0]], atol=1e-9)
    np.testing.assert_allclose(qdd, [np.zeros(3), tr.qdd[0]], atol=1e-8)


def test_messages_are_refused_naming_the_point():
    names = ["a", "b", "c"]
    point = {"positions": [0.0, 0.0, 0.0], "time_from_start": {"sec": 0, "nanosec": 0}}
    later = {"positions": [0.1, 0.0, 0.0], "time_from_start": {"sec": 1, "nanosec": 0}}
    good = {"joint_names": ["c", "a", "b"], "points": [point, later]}
    tr = Trajectory.from_message(good, names)
    np.testing.assert_array_equal(tr.q[1], [0.0, 0.0, 0.1])  # by name
    cases = {
        "not after point 0": {"joint_names": names, "points": [later, later]},
        "unknown joint": {"joint_names": ["a", "b", "x"], "points": [point, later]},
        "point 1: no positions": {"joint_names": names, "points": [point, {**later, "positions": []}]},
        "not a finite number": {"joint_names": names, "points": [point, {**later, "positions": [0, float("nan"), 0]}]},
        "accelerations without velocities": {
            "joint_names": names,
            "points": [point, {**later, "accelerations": [0, 0, 0]}],
        },
    }
    odd = {
        "not a JointTrajectory": ["points"],
        "joint_names: must be a list": {"joint_names": "a b c", "points": [point, later]},
        "need at least 2 points": {"joint_names": names, "points": [point]},
        "point 1: not a mapping": {"joint_names": names, "points": [point, [0.1, 0, 0]]},
        "positions of b is '0'": {"joint_names": names, "points": [point, {**later, "positions": [0.1, "0", 0]}]},
        "positions of a is True": {"joint_names": names, "points": [point, {**later, "positions": [True, 0, 0]}]},
        "must be 3 numbers": {"joint_names": names, "points": [point, {**later, "velocities": [0.0, 0.0]}]},
        "is not a duration": {
            "joint_names": names,
            "points": [point, {**later, "time_from_start": {"sec": 1, "nanosec": 10**9}}],
        },
        "must be .sec, nanosec.": {"joint_names": names, "points": [point, {**later, "time_from_start": 1.0}]},
        "duplicates": {"joint_names": ["a", "a", "b"], "points": [point, later]},
        "no c": {"joint_names": ["a", "b"], "points": [{**point, "positions": [0, 0]}, {**later, "positions": [0, 0]}]},
    }
    for reason, message in {**cases, **odd}.items():
        with pytest.raises(TrajectoryError, match=reason) as error:
            Trajectory.from_message(message, names)
        assert "\n" not in str(error.value)
