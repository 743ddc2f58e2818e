"""The recursions' rotations: an inertia turned about a coordinate axis by the double angle
(rotations.turned_about, the leaf links' and crba's) is R I R^T for either sign of each axis."""

import math

import numpy as np
import pytest

from irb140_dynamics.core.algorithms.rotations import turn, turned_about


def matrix(inertia):
    xx, yy, zz, xy, xz, yz = inertia
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


@pytest.mark.parametrize("sign", [1.0, -1.0])
@pytest.mark.parametrize("k", [0, 1, 2])
def test_an_inertia_turned_about_an_axis_is_r_i_r_transposed(k, sign):
    rng = np.random.default_rng(7 + k)
    A = rng.normal(size=(3, 3))
    S = A @ A.T
    inertia = (S[0, 0], S[1, 1], S[2, 2], S[0, 1], S[0, 2], S[1, 2])
    axis = tuple(sign if j == k else 0.0 for j in range(3))
    for theta in (0.3, 2.1, -1.2):
        rot = turn(axis, math.cos(theta), math.sin(theta))
        R = np.array(rot, dtype=float)
        assert np.allclose(matrix(turned_about(rot, inertia, k)), R @ matrix(inertia) @ R.T, rtol=0.0, atol=1e-14)
