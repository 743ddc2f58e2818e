"""The plot of ``retime --plot``: per joint, the share of each limit a trajectory uses over
time (torque, velocity, acceleration as % of the limit), before and after re-timing."""

from __future__ import annotations

import io

import numpy as np

from ..core.trajectories.check import QUANTITIES, profiles
from ..core.trajectories.interpolation import sample_times, spline
from ..figures import fit_text

COLORS = ("tab:green", "tab:blue", "tab:orange")  # torque, velocity, acceleration


def what_was_drawn(trajectory: str, arm: str, payload) -> str:
    """The plot's title: the trajectory's file, the arm's, the payload (mass, CoM)."""
    load = "no payload"
    if payload.mass > 0:
        com = ", ".join(f"{x:g}" for x in payload.com)
        load = f"payload {payload.mass:g} kg, CoM ({com}) m"
    return f"{trajectory} on {arm}, {load}: share of each limit used over time"


DPI = 100


def limit_use_png(model, limits, before, after=None, title: str = "share of each limit used over time") -> bytes:
    """PNG bytes (1200 px wide or more): a row per joint, a column per trajectory (before,
    after), a legend of the three limits above; ``title`` names what was drawn."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    columns = [("before re-timing", before)] + ([("after re-timing", after)] if after is not None else [])
    fig, axes = plt.subplots(
        model.n, len(columns), figsize=(max(12.0, 7 * len(columns)), 1.7 * model.n + 1.8), squeeze=False, dpi=DPI
    )
    for c, (heading, tr) in enumerate(columns):
        sp = spline(tr)
        t, seg = sample_times(sp, 16, 2e-3)
        values = profiles(model, sp, t, seg)
        for j, name in enumerate(model.joint_names):
            ax = axes[j, c]
            for quantity, color in zip(QUANTITIES, COLORS):
                limit = getattr(limits, quantity)[j]
                if np.isfinite(limit):
                    ax.plot(t, 100 * np.abs(values[quantity][:, j]) / limit, lw=1.2, color=color, label=quantity)
            ax.axhline(100, color="k", lw=0.8, ls="--")
            ax.set_ylabel(f"{name}\n% of limit")
            ax.grid(True, linewidth=0.3)
            if j < model.n - 1:
                ax.tick_params(labelbottom=False)
            if j == 0:
                ax.set_title(f"{heading}: {sp.end:.3f} s")
        axes[-1, c].set_xlabel("t [s]")
    for row in axes:  # a joint's row on one scale, before and after
        top = max(ax.get_ylim()[1] for ax in row)
        for ax in row:
            ax.set_ylim(0, top)
    handles = [
        matplotlib.lines.Line2D([], [], color=c, lw=2, label=f"{q} (% of its limit)")
        for q, c in zip(QUANTITIES, COLORS)
    ]
    handles.append(matplotlib.lines.Line2D([], [], color="k", lw=0.8, ls="--", label="the limit (100 %)"))
    fig.suptitle(title, fontsize=12)
    fit_text(fig, rect=(0, 0, 1, 0.93))
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.955), ncol=4, fontsize=10, frameon=False)
    out = io.BytesIO()
    fig.savefig(out, format="png", dpi=DPI)
    plt.close(fig)
    return out.getvalue()
