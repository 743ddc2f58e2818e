"""How the mass-matrix kernels lay out M: its upper triangle, row by row (M is symmetric)."""

from __future__ import annotations

from functools import cache

import numpy as np


@cache
def upper_to_full(n: int) -> np.ndarray:
    """For each entry of an n x n matrix, its index in the row-by-row upper triangle."""
    index = np.empty((n, n), dtype=np.intp)
    rows, cols = np.triu_indices(n)
    index[rows, cols] = index[cols, rows] = np.arange(len(rows))
    index.setflags(write=False)  # cached: shared by every caller
    return index


def whole_matrix(upper: list, n: int) -> list:
    """The n x n entries, row by row, of a symmetric matrix given by its upper triangle."""
    return [upper[i] for i in upper_to_full(n).ravel().tolist()]
