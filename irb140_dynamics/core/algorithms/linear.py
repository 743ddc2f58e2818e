"""Dense linear algebra on scalar components (any number type with + - * /, traced symbols
too): M^-1 of a symmetric positive definite M, products. Matrices are lists of rows."""

from __future__ import annotations


class SingularMatrix(ValueError):
    """A pivot of M = L D L^T is zero for every state (a joint that moves no inertia):
    ``index`` is its row."""

    def __init__(self, index: int):
        super().__init__(f"the mass matrix is singular: row {index} has no pivot")
        self.index = index


def inverse(M):
    """M^-1 of a symmetric positive definite M (rows), by M = L D L^T; the whole matrix,
    its entries below the diagonal the same values as those above."""
    n = len(M)
    L, inverse_D = factors(M)
    # U = L^-1 (unit lower triangular), column by column
    U = [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]
    for j in range(n):
        for i in range(j + 1, n):
            x = -L[i][j]
            for k in range(j + 1, i):
                x = x - L[i][k] * U[k][j]
            U[i][j] = x
    # M^-1 = U^T D^-1 U: entry (i, j), i <= j, sums over k >= j
    Minv = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i, n):
            x = U[j][i] * inverse_D[j] if i != j else inverse_D[j]
            for k in range(j + 1, n):
                x = x + U[k][i] * (U[k][j] * inverse_D[k])
            Minv[i][j] = Minv[j][i] = x
    return Minv


def factors(M):
    """(L, D^-1) of M = L D L^T (L unit lower triangular, rows; D^-1 its pivots' inverses),
    M symmetric positive definite. Raises SingularMatrix where a pivot is a folded zero (a
    traced M whose joint moves no inertia: singular for every state)."""
    n = len(M)
    L = [[0.0] * n for _ in range(n)]
    D = [0.0] * n
    inverse_D = [0.0] * n
    for j in range(n):
        LD = [L[j][k] * D[k] for k in range(j)]  # L_jk D_k
        d = M[j][j]
        for k in range(j):
            d = d - LD[k] * L[j][k]
        if isinstance(d, float) and d == 0.0:  # a folded zero: so for every state
            raise SingularMatrix(j)
        D[j], inverse_D[j] = d, 1.0 / d
        for i in range(j + 1, n):
            x = M[i][j]
            for k in range(j):
                x = x - L[i][k] * LD[k]
            L[i][j] = x * inverse_D[j]
    return L, inverse_D


def times(A, B):
    """The matrix product A B (rows)."""
    columns = list(zip(*B))
    return [[_dot(row, column) for column in columns] for row in A]


def times_vector(A, v):
    return [_dot(row, v) for row in A]


def _dot(u, v):
    total = None
    for x, y in zip(u, v):
        if isinstance(x, float) and x == 0.0 or isinstance(y, float) and y == 0.0:
            continue
        term = x * y
        total = term if total is None else total + term
    return 0.0 if total is None else total


def negated(A):
    return [[-x for x in row] for row in A]
