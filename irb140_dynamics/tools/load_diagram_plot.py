"""The files of ``load_diagram``: the diagram as CSV, and as a PNG drawn as vendors draw it
(L, the CoM's distance off the flange axis, across; Z, along it, up; mass contours; the
rated payload's curve in bold)."""

from __future__ import annotations

import io
import math

import numpy as np

COLUMNS = ("z_m", "l_m", "max_mass_kg", "status", "limiting_joint", "reason")


def mass_text(point) -> str:
    """A proven mass rounded down to the gram's thousandth (a lower bound stays one); an
    unproven one as found; empty where there is none."""
    if not math.isfinite(point.mass):
        return ""
    if point.proven:
        return f"{math.floor(point.mass * 1e6) / 1e6:.6f}"
    return f"{point.mass:.6f}"


def diagram_csv(diagram) -> str:
    """One row per CoM position, z outer, l inner; a reason only for unproven rows."""
    lines = [",".join(COLUMNS)]
    for p in diagram.points:
        joint = "" if p.joint is None else diagram.joint_names[p.joint]
        reason = p.reason.replace('"', "'")
        cells = [f"{p.z:.6f}", f"{p.l:.6f}", mass_text(p), "proven" if p.proven else "unproven", joint]
        lines.append(",".join(cells + [f'"{reason}"' if reason else ""]))
    return "\n".join(lines) + "\n"


def diagram_png(diagram, rated_mass: float, arm: str) -> bytes:
    """PNG bytes: filled mass contours over L (across) and Z (up), labelled lines, the rated
    mass's curve in bold (or, where no point holds it, the note of where it does), unproven
    points crossed; ``arm`` names the arm in the title."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    masses = np.where(np.isfinite(diagram.masses()), diagram.masses(), np.nan)
    fig, ax = plt.subplots(figsize=(6.4, 6.4), layout="constrained")
    L, Z = np.meshgrid(diagram.l, diagram.z)
    finite = masses[np.isfinite(masses)]
    if diagram.z.size > 1 and diagram.l.size > 1 and finite.size and finite.max() > finite.min():
        levels = _levels(finite.min(), finite.max())
        filled = ax.contourf(L, Z, masses, levels=levels, cmap="viridis_r", extend="both")
        lines = ax.contour(L, Z, masses, levels=levels, colors="k", linewidths=0.6)
        ax.clabel(lines, fmt="%g kg", fontsize=7)
        fig.colorbar(filled, ax=ax, label="largest payload [kg]", shrink=0.8)
        if finite.min() <= rated_mass <= finite.max():
            rated = ax.contour(L, Z, masses, levels=[rated_mass], colors="tab:red", linewidths=2.5)
            ax.clabel(rated, fmt=f"rated {rated_mass:g} kg", fontsize=8)
    if not (finite.size and finite.min() <= rated_mass <= finite.max()):
        if finite.size and rated_mass > finite.max():
            where = f"more than any point holds (at most {finite.max():.3f} kg)"
        else:
            where = "less than every point holds"
        ax.plot([0], [0], "o", color="tab:red", label=f"rated {rated_mass:g} kg: {where}")
    else:
        points = ax.scatter(L, Z, c=masses, cmap="viridis_r")
        fig.colorbar(points, ax=ax, label="largest payload [kg]", shrink=0.8)
    unproven = np.array([not p.proven for p in diagram.points]).reshape(masses.shape)
    if unproven.any():
        ax.plot(L[unproven], Z[unproven], "x", color="tab:red", label="unproven")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize="small")
    ax.set_xlabel("L: CoM off the flange axis, any direction [m]")
    ax.set_ylabel("Z: CoM along the flange axis [m]")
    ax.set_aspect("equal", adjustable="box")
    ax.set_title(
        f"Load diagram: {arm} ({len(diagram.joint_names)} joints), at rest in every pose\n"
        f"largest payload [kg], {100 * diagram.proven_share:.0f} % proven",
        fontsize=10,
    )
    out = io.BytesIO()
    fig.savefig(out, format="png", dpi=80)
    plt.close(fig)
    return out.getvalue()


def _levels(low: float, high: float) -> np.ndarray:
    """Round masses spread evenly on a log scale over [low, high], at most a dozen (as a
    vendor labels the curves: dense where the masses are small)."""
    ladder = np.array([k * 10.0**e for e in range(-3, 7) for k in (1, 1.25, 1.5, 2, 2.5, 3, 4, 5, 6, 8)])
    inside = ladder[(ladder >= low) & (ladder <= high)]
    if inside.size < 3:
        return np.linspace(low, high, 6)
    return inside[np.unique(np.linspace(0, inside.size - 1, min(12, inside.size)).round().astype(int))]
