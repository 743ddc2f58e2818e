"""The plot of ``retime --plot``: per joint, the share of each limit a trajectory uses over
time (torque, velocity, acceleration as % of the limit), before and after re-timing."""

from __future__ import annotations

import io

import numpy as np

from ..core.trajectories.check import QUANTITIES, profiles
from ..core.trajectories.interpolation import sample_times, spline
from ..figures import fit_text

COLORS = ("tab:green", "tab:blue", "tab:orange")  # torque, velocity, acceleration


def limit_use_png(model, limits, before, after=None) -> bytes:
    """PNG bytes: a row per joint, a column per trajectory (before, after)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    columns = [("before", before)] + ([("after", after)] if after is not None else [])
    fig, axes = plt.subplots(
        model.n, len(columns), figsize=(6 * len(columns), 1.6 * model.n + 1), sharey=True, squeeze=False
    )
    for c, (title, tr) in enumerate(columns):
        sp = spline(tr)
        t, seg = sample_times(sp, 16, 2e-3)
        values = profiles(model, sp, t, seg)
        for j, name in enumerate(model.joint_names):
            ax = axes[j, c]
            for quantity, color in zip(QUANTITIES, COLORS):
                limit = getattr(limits, quantity)[j]
                if np.isfinite(limit):
                    ax.plot(t, 100 * np.abs(values[quantity][:, j]) / limit, lw=1, color=color, label=quantity)
            ax.axhline(100, color="k", lw=0.8, ls="--")
            ax.set_ylabel(f"{name}\n% of limit")
            if j == 0:
                ax.set_title(f"{title}: {sp.end:.3f} s")
        axes[-1, c].set_xlabel("t [s]")
    handles = [matplotlib.lines.Line2D([], [], color=c, label=q) for q, c in zip(QUANTITIES, COLORS)]
    fig.legend(handles=handles, loc="upper center", ncol=3, fontsize="small")
    fit_text(fig, rect=(0, 0, 1, 0.97))
    out = io.BytesIO()
    fig.savefig(out, format="png", dpi=80)
    plt.close(fig)
    return out.getvalue()
