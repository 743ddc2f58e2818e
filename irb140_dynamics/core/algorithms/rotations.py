"""Rotations of the recursions: applying a constant or joint rotation to a vector with the
constant coefficients 0 and +-1 left out, a joint's Rot(u, theta), and a joint's three
rotations (R0 Rot R1) made one."""

from __future__ import annotations

from dataclasses import replace

Rotation = tuple[tuple[float, float, float], ...]


def combination(terms):
    """sum of coef * x, with the constant coefficients 0 and +-1 left out."""
    total = None
    for coef, x in terms:
        if isinstance(coef, float):
            if coef == 0.0:
                continue
            term = x if coef == 1.0 else -x if coef == -1.0 else coef * x
        else:
            term = coef * x
        total = term if total is None else total + term
    return 0.0 if total is None else total


def rotate(R, v):
    """R v."""
    return tuple(combination(zip(R[j], v)) for j in range(3))


def rotate_back(R, v):
    """R^T v."""
    return tuple(combination((R[k][j], v[k]) for k in range(3)) for j in range(3))


def _parts(u) -> tuple[Rotation, Rotation, Rotation]:
    """(1 - u u^T, [u]x, u u^T): Rot(u, theta) = c (1 - u u^T) + s [u]x + u u^T."""
    outer = tuple(tuple(u[j] * u[k] for k in range(3)) for j in range(3))
    return (
        tuple(tuple((1.0 if j == k else 0.0) - outer[j][k] for k in range(3)) for j in range(3)),
        ((0.0, -u[2], u[1]), (u[2], 0.0, -u[0]), (-u[1], u[0], 0.0)),
        outer,
    )


def turn(u, c, s) -> Rotation:
    """Rot(u, theta) (see ``_parts``), given c, s of theta."""
    across, skew, outer = _parts(u)
    rows = []
    for j in range(3):
        row = []
        for k in range(3):
            entry = combination(((across[j][k], c), (skew[j][k], s)))
            row.append(entry + outer[j][k] if outer[j][k] else entry)
        rows.append(tuple(row))
    return tuple(rows)


def fused(links, cs, moves):
    """(links, moves) from ``moves`` (``steps``' (Rot, p0) of each joint), with a revolute joint's R0 Rot R1 made one
    rotation, c A + s B + C (A, B, C constants), where R0 or R1 does more than permute: a
    vector then turns in one step instead of three, fewer operations and a shorter
    dependent path through the recursions."""
    fused_links, fused_moves = [], []
    for link, x, move in zip(links, cs, moves):
        if link.prismatic or (_permutes(link.R0) and _permutes(link.R1)):
            fused_links.append(link)
            fused_moves.append(move)
            continue
        A, B, C = (_times(_times(link.R0, part), link.R1) for part in _parts(link.u))
        entries = [[combination(((A[j][k], x[0]), (B[j][k], x[1]))) for k in range(3)] for j in range(3)]
        rot = tuple(tuple(e + C[j][k] if C[j][k] else e for k, e in enumerate(row)) for j, row in enumerate(entries))
        fused_links.append(replace(link, R0=None, R1=None))
        fused_moves.append((rot, link.p0))
    return fused_links, fused_moves


def _permutes(R) -> bool:
    """Whether R (None: identity) only reorders and negates components: free to apply."""
    return R is None or all(x in (0.0, 1.0, -1.0) for row in R for x in row)


def _times(R, S):
    """R S of constant 3x3 matrices (None: identity)."""
    if R is None or S is None:
        return S if R is None else R
    return tuple(tuple(R[j][0] * S[0][k] + R[j][1] * S[1][k] + R[j][2] * S[2][k] for k in range(3)) for j in range(3))


def turned(R, inertia):
    """R I R^T of an inertia (xx, yy, zz, xy, xz, yz): columns of R I, then R (R I)^T."""
    xx, yy, zz, xy, xz, yz = inertia
    rows_of_ri = list(zip(*(rotate(R, col) for col in ((xx, xy, xz), (xy, yy, yz), (xz, yz, zz)))))
    col0, col1, col2 = (rotate(R, row) for row in rows_of_ri)
    return (col0[0], col1[1], col2[2], col1[0], col2[0], col2[1])


INERTIA_INDEX = {  # (row, column) -> the entry of (xx, yy, zz, xy, xz, yz)
    (0, 0): 0,
    (1, 1): 1,
    (2, 2): 2,
    (0, 1): 3,
    (1, 0): 3,
    (0, 2): 4,
    (2, 0): 4,
    (1, 2): 5,
    (2, 1): 5,
}


def turned_about(rot, inertia, k: int):
    """Rot I Rot^T for a turn ``rot`` about the coordinate axis k (either sign) by the double
    angle: in the turn's plane (i, j) = (k+1, k+2), with C = cos 2t, S = sin 2t, the ii, jj,
    ij block turns by 2t about its mean; ik, jk turn by t; kk stays."""
    i, j = (k + 1) % 3, (k + 2) % 3
    c, s = rot[i][i], rot[j][i]
    ii, jj, kk, ij, ik, jk = (inertia[INERTIA_INDEX[pair]] for pair in ((i, i), (j, j), (k, k), (i, j), (i, k), (j, k)))
    C, S = c * c - s * s, (c * s) * 2.0
    mean, half = (ii + jj) * 0.5, (ii - jj) * 0.5
    x = half * C - ij * S
    out = [None] * 6
    for pair, value in (
        ((i, i), mean + x),
        ((j, j), mean - x),
        ((k, k), kk),
        ((i, j), half * S + ij * C),
        ((i, k), c * ik - s * jk),
        ((j, k), s * ik + c * jk),
    ):
        out[INERTIA_INDEX[pair]] = value
    return tuple(out)
