"""Plain interval bounds of static torques over a box of joint values: the proof for arms
beyond ``harmonic.MAX_JOINTS`` joints, whose harmonic sums would be too large.

Units: rad (m for a prismatic joint), N m. Loose, but proven: each box's torques are
enclosed by evaluating the recursion on Interval numbers (``evaluate``); boxes are bisected
along their widest joint while the work budget (and the analysis' time, see ``stop``) lasts.
"""

from __future__ import annotations

import numpy as np

from irb140_dynamics.core.payload.stop import out_of_time

INTERVAL_WORK = 20_000  # box x joint evaluations of plain interval bounds (beyond harmonic.MAX_JOINTS)


def interval_maxima(evaluate, joints, signs, lower, upper, incumbent, tol, work: int = INTERVAL_WORK):
    """Upper bounds of sign_k tau[joint_k] over q in [lower, upper] (n,), from plain
    interval evaluations ``evaluate(lo, hi)`` -> (lo, hi) of the torques (n, B) over boxes
    (B, n), bisecting the widest joint range while ``work`` (and the analysis' time) lasts:
    loose, but proven."""
    K, n = len(joints), len(lower)
    lo, hi, owner = np.tile(lower, (K, 1)), np.tile(upper, (K, 1)), np.arange(K)
    inherited, closed, spent = np.full(K, np.inf), np.full(K, -np.inf), 0
    while owner.size and spent + owner.size * n <= work and not out_of_time():
        low, high = evaluate(lo, hi)
        box = np.arange(owner.size)
        bound = np.where(signs[owner] > 0, high[joints[owner], box], -low[joints[owner], box])
        spent += owner.size * n
        kept = bound >= incumbent[owner]
        done = kept & (bound <= incumbent[owner] + tol[owner])
        np.maximum.at(closed, owner[done], bound[done])
        split = kept & ~done
        lo, hi, owner, inherited = lo[split], hi[split], owner[split], bound[split]
        axis = np.argmax(hi - lo, axis=1)
        rows = np.arange(owner.size)
        middle = 0.5 * (lo[rows, axis] + hi[rows, axis])
        left_hi, right_lo = hi.copy(), lo.copy()
        left_hi[rows, axis], right_lo[rows, axis] = middle, middle
        lo, hi = np.concatenate([lo, right_lo]), np.concatenate([left_hi, hi])
        owner, inherited = np.concatenate([owner, owner]), np.concatenate([inherited, inherited])
    result = np.maximum(np.asarray(incumbent, dtype=float), closed)
    np.maximum.at(result, owner, inherited)
    return result
