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
