"""PNG plots of an identification (matplotlib): measured against predicted torques, residuals."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

import numpy as np

from irb140_dynamics.core.regressor import inertial_parameters, regressor_batch
from irb140_dynamics.figures import fit_text
from irb140_dynamics.identification.pipeline import Result

DPI = 100
Save = Callable[[str, Callable[[BinaryIO], None]], None]  # (file name, writer of its bytes)


def write_plots(result: Result, directory: str | Path | Save, arm: str) -> list[str]:
    """torques.png and residuals.png of the held-out fit points, in ``directory`` or, when it
    is a ``Save`` function, through it (the tools stage them: all outputs or none); their names.
    Their titles name what was drawn: ``arm`` (its name and file) and the recording held out."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    points = result.plot_points
    if points is None or len(points) == 0:
        return []
    if callable(directory):
        save = directory
    else:
        folder = Path(directory)
        folder.mkdir(parents=True, exist_ok=True)

        def save(name, write):
            with open(folder / name, "wb") as stream:
                write(stream)

    order = np.argsort(points.time)
    time = points.time[order] - points.time[order][0]
    Y = regressor_batch(result.prior, points.q[order], points.qd[order], points.qdd[order])
    measured = points.tau[order]
    predicted = {"prior": Y @ inertial_parameters(result.prior), "identified": Y @ result.fit.pi}
    names = result.prior.joint_names
    n = len(names)
    written = []
    for kind in ("torques", "residuals"):
        figure, axes = plt.subplots(n, 1, figsize=(12, 1.9 * n + 1.8), sharex=True, squeeze=False, dpi=DPI)
        for j, axis in enumerate(axes[:, 0]):
            if kind == "torques":
                axis.plot(time, measured[:, j], "k.", markersize=2, label="measured")
                axis.plot(time, predicted["prior"][:, j], color="tab:orange", linewidth=1, label="prior model")
                axis.plot(time, predicted["identified"][:, j], color="tab:blue", linewidth=1, label="identified")
            else:
                for model, colour in (("prior", "tab:orange"), ("identified", "tab:blue")):
                    residual = measured[:, j] - predicted[model][:, j]
                    axis.plot(time, residual, ".", color=colour, markersize=2, label=f"measured - {model}")
                axis.axhline(0.0, color="k", linewidth=0.5)
            axis.set_ylabel(f"{names[j]}\n[N m]")
            axis.grid(True, linewidth=0.3)
            axis.margins(y=0.08)  # every point inside, none on the frame
        axes[-1, 0].set_xlabel("time [s] (held-out fit points)")
        figure.suptitle(f"{kind.capitalize()} of {arm} on held-out data: {held_out(result)}", fontsize=12)
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fit_text(figure, rect=(0, 0, 1, 0.95))  # the title names the held-out recording's path: wrapped, never cut
        top = max(axis.get_position().y1 for axis in axes[:, 0])
        figure.legend(  # above the panels, over no data
            handles, labels, loc="lower center", bbox_to_anchor=(0.5, top), ncol=3, markerscale=4, frameon=False
        )
        try:
            save(f"{kind}.png", lambda stream, figure=figure: figure.savefig(stream, format="png", dpi=DPI))
        finally:
            plt.close(figure)
        written.append(f"{kind}.png")
    return written


def held_out(result: Result) -> str:
    """Which recording's points were held out, by its path: a --validate recording's name is
    the source itself; else the fitted recording's part, with the recording named."""
    if len(result.tallies) > 1:
        return result.held_out_source
    return f"{result.held_out_source} {result.tallies[0].path}"
