"""The demo's tracking plot (``demo_tracking.png``): per joint, the reference and actual
positions over the last seconds (where a sine reads as one), and the tracking error over
the whole run (matplotlib; imports nothing of the package but ``figures``).

Units: s, rad; the error in mrad (reference - actual).
"""

from __future__ import annotations

import numpy as np

from irb140_dynamics.figures import clear_legend, fit_text

WINDOW = 10.0  # s of positions shown: the run's last
DPI = 100


def write_tracking_plot(path, t, reference, actual, joint_names, label: str) -> None:
    """Write the PNG to ``path`` (a file name or a binary stream): ``t`` (N,) s, ``reference``
    and ``actual`` (N, n) rad, ``label`` saying which model drives which arm (in the title)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.asarray(t, dtype=float)
    reference, actual = np.asarray(reference, dtype=float), np.asarray(actual, dtype=float)
    n = reference.shape[1]
    error = 1e3 * (reference - actual)
    shown = t >= t[-1] - WINDOW
    figure, axes = plt.subplots(n, 2, figsize=(14, 1.9 * n + 1.6), squeeze=False, dpi=DPI)
    for j, name in enumerate(joint_names):
        position, tracking = axes[j]
        position.plot(t[shown], reference[shown, j], color="tab:blue", label="reference")
        position.plot(t[shown], actual[shown, j], "--", color="tab:orange", label="actual")
        position.set_ylabel(f"{name}\nq [rad]")
        rms = float(np.sqrt(np.mean(error[:, j] ** 2)))
        tracking.plot(t, error[:, j], color="tab:red", linewidth=0.8, label="reference - actual")
        tracking.axhline(0.0, color="k", linewidth=0.5)
        tracking.set_ylabel(f"{name}\nerror [mrad]")
        tracking.set_title(f"{name}: RMS {rms:.2f} mrad, largest {np.max(np.abs(error[:, j])):.2f} mrad", fontsize=9)
        for axis in (position, tracking):
            axis.grid(True, linewidth=0.3)
            if j < n - 1:
                axis.tick_params(labelbottom=False)
    since = f"the last {WINDOW:g} s" if t[-1] - t[0] > WINDOW else "the whole run"
    axes[0, 0].set_title(f"positions over {since}", fontsize=10)
    axes[0, 0].legend(
        loc="best", fontsize=9, ncol=2, framealpha=0.9
    )  # (moved where it covers no line after the layout)
    axes[-1, 0].set_xlabel("t [s]")
    axes[-1, 1].set_xlabel("t [s]")
    figure.suptitle(
        f"demo_node: joint tracking over {t[-1] - t[0]:.1f} s, left the positions, right the error ({label})",
        fontsize=11,
    )
    fit_text(figure)
    clear_legend(axes[0, 0], fontsize=9, ncol=2, framealpha=0.9)
    try:
        figure.savefig(path, format="png", dpi=DPI)
    finally:
        plt.close(figure)
