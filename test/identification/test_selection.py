"""Which fit points identify uses: rest trimmed at both ends, the held-out part chosen among
the points that move (identification/selection.py)."""

import numpy as np

from irb140_dynamics.identification.selection import rows_used, select


def test_rest_is_trimmed_and_the_last_fifth_of_the_moving_points_held_out():
    moves = np.zeros(100, bool)
    moves[10:60] = True  # 50 moving points, rest before (10) and after (40)
    moves[30] = False  # a pause within the motion stays in
    s = select(moves, 0.2)
    assert (s.first, s.end, s.moving) == (10, 60, 49)
    assert s.held_moving == 10 and np.count_nonzero(moves[s.held]) == 10  # ceil(0.2 * 49)
    assert np.count_nonzero(moves[s.train]) == 39 and s.split == 50


def test_held_out_is_never_all_nor_nothing_and_nothing_moving_is_none():
    assert select(np.zeros(20, bool), 0.2) is None
    one = np.zeros(20, bool)
    one[[3, 7]] = True
    s = select(one, 0.01)
    assert (s.train, s.held, s.held_moving) == (slice(3, 7), slice(7, 8), 1)
    s = select(one, 0.99)
    assert s.held_moving == 1 and s.split == 7  # one point left to fit
    assert select(one, 0.0).held == slice(8, 8)  # a recording fitted whole (--validate)
    assert select(one, 1.0).train == slice(3, 3)  # a validation recording, all held out


def test_a_row_is_used_from_min_speed_on_with_the_acceleration_margin():
    qd = np.array([[0.0, 0.1, -0.2], [0.05, 0.3, 0.0]])
    qdd = np.array([[0.0, 0.0, 1.0], [0.0, 10.0, 0.0]])
    used = rows_used(qd, qdd, min_speed=0.1, half_window=0.01)
    # |qd| >= 0.1 + |qdd| * 0.01: 0.1 >= 0.1, 0.2 >= 0.11; 0.05 < 0.1; 0.3 >= 0.2
    np.testing.assert_array_equal(used, [[False, True, True], [False, True, False]])
