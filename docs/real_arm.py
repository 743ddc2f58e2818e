"""The numbers and the plot of docs/real-arm.md: the KUKA LWR4+ of test/data/kuka_lwr4.

    .venv/bin/python docs/real_arm.py            # prints the tables, writes docs/real_arm.png

Identifies on traj1 with the URDF as the prior (the defaults of `identify`), validates on
traj3, and compares with the URDF prior (no friction) and plain least squares (the base
parameters without armature, unweighted), on the held-out moving samples (what `identify`
prints) and on all held-out fit points. Also with --prior-weight 0.1 and 10 and with
--offsets, to show how the choice matters.
"""

from __future__ import annotations

import lzma
import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from irb140_dynamics.core.io.arm_source import read_arm, read_urdf_file  # noqa: E402
from irb140_dynamics.core.regressor import inertial_parameters, regressor_batch  # noqa: E402
from irb140_dynamics.identification.pipeline import IdentificationSettings, identify  # noqa: E402

KUKA = ROOT / "test" / "data" / "kuka_lwr4"


def plain_least_squares(result) -> np.ndarray:
    """Unweighted least squares, base parameters without armature; ``result`` of min_speed 0 (every row)."""
    n = result.prior.n
    columns = np.setdiff1d(result.base.independent, 10 * n + 3 * np.arange(n) + 2)
    pi = np.zeros(13 * n)
    pi[columns] = np.linalg.solve(
        result.train.A.sum(axis=0)[np.ix_(columns, columns)], result.train.b.sum(axis=0)[columns]
    )
    return pi


def all_points_rms(result, pi, offsets=None) -> np.ndarray:
    """RMS over every held-out fit point kept for the plots (moving or not)."""
    points = result.plot_points
    Y = regressor_batch(result.prior, points.q, points.qd, points.qdd)
    error = Y @ pi + (0.0 if offsets is None else offsets) - points.tau
    return np.sqrt(np.mean(error**2, axis=0))


def table(rows: dict, peak: np.ndarray, names) -> str:
    lines = ["| joint | peak [N m] | " + " | ".join(rows) + " |", "|---|---:|" + "---:|" * len(rows)]
    for j, name in enumerate(names):
        cells = [f"{row[j]:.3f} ({100 * row[j] / peak[j]:.1f} %)" for row in rows.values()]
        lines.append(f"| {j + 1} `{name}` | {peak[j]:.2f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    folder = Path(tempfile.mkdtemp())
    for name in ("traj1", "traj3"):
        (folder / f"{name}.csv").write_bytes(lzma.decompress((KUKA / f"{name}.csv.xz").read_bytes()))
    prior = read_arm({}, urdf=read_urdf_file(KUKA / "kuka_lwr4.urdf")).model
    runs = {}
    for label, settings in [
        ("ours (default)", IdentificationSettings()),
        ("weight 0.1", IdentificationSettings(prior_weight=0.1)),
        ("weight 10", IdentificationSettings(prior_weight=10.0)),
        ("--offsets", IdentificationSettings(offsets=True)),
        ("every row", IdentificationSettings(min_speed=0.0)),
    ]:
        runs[label] = identify(prior, folder / "traj1.csv", settings, validate=folder / "traj3.csv")
    result = runs["ours (default)"]
    n, names = prior.n, prior.joint_names
    prior_pi = inertial_parameters(prior)
    prior_pi[10 * n :] = 0.0
    plain = plain_least_squares(runs.pop("every row"))
    peak = result.held_out.peak
    moving = {
        "URDF prior": result.held_out.rms(prior_pi),
        "plain LS": result.held_out.rms(plain),
        "ours": result.rms("identified"),
    }
    print("held-out moving samples (what identify prints), RMS [N m] (% of peak):")
    print(table(moving, peak, names))
    print(
        f"\nresidual correlation {result.correlation:.1f} fit points, filter's own "
        f"{result.tallies[0].design.noise_correlation():.2f}; chi2 {result.physical.chi2:.1f} "
        f"(bound {result.physical.bound:.1f})\n"
    )
    every = {
        "URDF prior": all_points_rms(result, prior_pi),
        "plain LS": all_points_rms(result, plain),
        "ours": all_points_rms(result, result.fit.pi),
    }
    print("all held-out fit points:")
    print(table(every, peak, names))
    print("\nother settings, moving samples:")
    print(table({label: r.rms("identified") for label, r in runs.items()}, peak, names))
    plot(result, prior_pi, plain, moving, peak, ROOT / "docs" / "real_arm.png")


def plot(result, prior_pi, plain, moving, peak, path: Path) -> None:
    """Held-out errors per joint (bars), and the torques of joints 2 and 4 along traj3; one
    legend above the panels, over no data; the title names the arm and the recordings."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from irb140_dynamics.figures import fit_text

    names = result.prior.joint_names
    figure, axes = plt.subplots(1, 3, figsize=(15, 4.6), gridspec_kw={"width_ratios": [1.2, 1, 1]})
    width = 0.27
    for k, (label, rms) in enumerate(moving.items()):
        axes[0].bar(np.arange(len(names)) + (k - 1) * width, 100 * rms / peak, width, label=label)
    axes[0].set_xticks(np.arange(len(names)), [str(j + 1) for j in range(len(names))])
    axes[0].set_yscale("log")
    axes[0].set(xlabel="joint", ylabel="held-out RMS error [% of peak]", title="held-out RMS error per joint")
    points = result.plot_points
    order = np.argsort(points.time)
    t = points.time[order] - points.time[order][0]
    Y = regressor_batch(result.prior, points.q[order], points.qd[order], points.qdd[order])
    for axis, j in zip(axes[1:], (1, 3)):
        axis.plot(t, points.tau[order, j], "k", lw=1.2, label="measured")
        axis.plot(t, Y[:, j] @ prior_pi, lw=0.9, label="URDF prior")
        axis.plot(t, Y[:, j] @ plain, lw=0.9, label="plain LS")
        axis.plot(t, Y[:, j] @ result.fit.pi, lw=0.9, label="ours")
        axis.set(xlabel="t [s]", ylabel="torque [N m]", title=f"joint {j + 1} ({names[j]}) along traj3")
    figure.suptitle(
        f"KUKA LWR4+ ({KUKA.name}/{KUKA.name}.urdf): identified on traj1.csv, predicting the held-out traj3.csv",
        fontsize=12,
    )
    fit_text(figure, rect=(0.0, 0.0, 1.0, 0.9))
    renderer = figure.canvas.get_renderer()
    top = max(axis.title.get_window_extent(renderer).y1 for axis in axes) / figure.bbox.height  # above the titles
    figure.legend(  # the same four colours in every panel: one legend, above the panels
        *axes[1].get_legend_handles_labels(), loc="lower center", bbox_to_anchor=(0.5, top), ncol=4, frameon=False
    )
    figure.savefig(path, dpi=90)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
