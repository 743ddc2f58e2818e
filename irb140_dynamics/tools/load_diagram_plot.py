"""The files of ``load_diagram``: the diagram as CSV, and as a PNG drawn as vendors draw it
(L, the CoM's distance off the flange axis, across; Z, along it, up; mass contours; the
rated payload's curve in bold)."""

from __future__ import annotations

import io
import math

import numpy as np

from irb140_dynamics.core.errors import counted

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


def diagram_png(diagram, arm: str, rated_mass: float | None = None) -> bytes:
    """PNG bytes (1300 x 650 px), two panels: the mass contours over L (across) and Z (up),
    labelled, a colour key of round, even steps, unproven points crossed; and the spec-sheet
    form, the largest mass against Z for a few L (one line each, a legend). ``rated_mass``
    [kg], where the arm states one: its curve in bold red (or a note where no point holds
    it) and a dashed line at it. ``arm`` names the arm in the title. The plane's legend
    stands below the panels (a legend inside would cover contours or crossed points), and
    the axes of Z and L start at 0 however few points (one point included)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from irb140_dynamics.figures import clear_legend, fit_text, label_curves

    masses = np.where(np.isfinite(diagram.masses()), diagram.masses(), np.nan)
    finite = masses[np.isfinite(masses)]
    unproven = np.array([not p.proven for p in diagram.points]).reshape(masses.shape)
    fig, (plane, sheet) = plt.subplots(1, 2, figsize=(13, 6.5), dpi=DPI)
    fig.suptitle(_title(diagram, arm, rated_mass, finite), fontsize=12)
    L, Z = np.meshgrid(diagram.l, diagram.z)
    contoured = diagram.z.size > 1 and diagram.l.size > 1 and finite.size and finite.max() > finite.min()
    if contoured:
        levels = _levels(finite.min(), finite.max())
        filled = plane.contourf(L, Z, masses, levels=levels, cmap="viridis_r")
        lines = plane.contour(L, Z, masses, levels=levels, colors="k", linewidths=0.6)
        fig.colorbar(filled, ax=plane, label="largest payload [kg]", ticks=levels)
    elif finite.size:
        points = plane.scatter(L, Z, c=masses, cmap="viridis_r", s=60)
        fig.colorbar(points, ax=plane, label="largest payload [kg]")
    if not contoured:  # (filled contours span the grid, 0 to its largest value, themselves)
        plane.set_xlim(*from_zero(diagram.l))
        plane.set_ylim(*from_zero(diagram.z))
    rated = None
    if contoured and rated_mass is not None and finite.min() <= rated_mass <= finite.max():
        rated = plane.contour(L, Z, masses, levels=[rated_mass], colors="tab:red", linewidths=2.5)
        plane.plot([], [], color="tab:red", linewidth=2.5, label=f"rated payload {rated_mass:g} kg")
    if unproven.any():
        plane.plot(L[unproven], Z[unproven], "x", color="tab:red", label="unproven (the mass a pose found)")
    plane.set_xlabel("L: CoM off the flange axis, any direction [m]")
    plane.set_ylabel("Z: CoM along the flange axis [m]")
    plane.set_title("largest payload [kg] over the CoM's position")
    handles, labels = plane.get_legend_handles_labels()
    if handles:  # below the panels: over no contour, no crossed point
        fig.legend(handles, labels, loc="lower center", bbox_to_anchor=(0.5, 0.0), ncol=len(handles), fontsize=9)
    _sheet(sheet, diagram, masses, unproven, rated_mass)
    rect = (0.0, LEGEND_BAND if handles else 0.0, 1.0, 1.0)
    fit_text(fig, rect)
    clear_legend(sheet, rect, fontsize=9, framealpha=0.9)
    if contoured:  # after the layout: the labels are placed where they fit
        label_curves(plane, lines, [f"{level:g} kg" for level in levels])
        if rated is not None:
            label_curves(plane, rated, [f"rated {rated_mass:g} kg"], color="tab:red", fontweight="bold")
    out = io.BytesIO()
    fig.savefig(out, format="png", dpi=DPI)
    plt.close(fig)
    return out.getvalue()


DPI = 100
SHEET_LINES = 5  # the spec-sheet form: at most this many values of L
LEGEND_BAND = 0.055  # of the figure's height: the band below the panels that holds the plane's legend
LEAST_SPAN = 0.1  # m: the shortest axis of Z or L drawn (a grid of one value, 0 included)


def from_zero(values) -> tuple[float, float]:
    """Axis limits [m] for grid values >= 0: from 0 (a margin of 4 % either side, which
    labels no negative value) to the largest value, over at least LEAST_SPAN."""
    high = max(float(np.max(values)), LEAST_SPAN)
    return -0.04 * high, 1.04 * high


def _title(diagram, arm: str, rated_mass, finite) -> str:
    joints = len(diagram.joint_names)
    first = f"Load diagram of {arm} ({joints} joints): the largest payload held at rest in every pose"
    second = f"{100 * diagram.proven_share:.0f} % of {counted(len(diagram.points), 'point')} proven"
    if rated_mass is None:
        second += "; no rated payload stated"
    elif finite.size and rated_mass > finite.max():
        second += f"; rated payload {rated_mass:g} kg: more than any point holds (at most {finite.max():.3g} kg)"
    elif finite.size and rated_mass < finite.min():
        second += f"; rated payload {rated_mass:g} kg: less than every point holds"
    else:
        second += f"; rated payload {rated_mass:g} kg"
    return first + "\n" + second


def _sheet(axes, diagram, masses, unproven, rated_mass) -> None:
    """The spec-sheet form: mass against Z, a line per L (a few, evenly chosen)."""
    columns = np.unique(np.linspace(0, diagram.l.size - 1, min(SHEET_LINES, diagram.l.size)).round().astype(int))
    colours = matplotlib_colours(len(columns))
    for colour, k in zip(colours, columns):
        axes.plot(diagram.z, masses[:, k], "o-", color=colour, markersize=4, label=f"L = {diagram.l[k]:g} m")
        crossed = unproven[:, k]
        if crossed.any():
            axes.plot(diagram.z[crossed], masses[crossed, k], "x", color="tab:red", markersize=8)
    if rated_mass is not None:
        axes.axhline(rated_mass, color="tab:red", linestyle="--", linewidth=1.5, label=f"rated {rated_mass:g} kg")
    axes.set_xlim(*from_zero(diagram.z))
    axes.set_xlabel("Z: CoM along the flange axis [m]")
    axes.set_ylabel("largest payload [kg]")
    axes.set_title("spec-sheet form: largest payload against Z, per L")
    axes.grid(True, linewidth=0.3)
    axes.legend(loc="best", fontsize=9, framealpha=0.9)  # (moved where it covers no line after the layout)


def matplotlib_colours(count: int):
    """``count`` colours of the diagram's colour map, dark (near the flange) to light."""
    import matplotlib

    return [matplotlib.colormaps["plasma"](x) for x in np.linspace(0.0, 0.8, max(count, 1))]


def _levels(low: float, high: float) -> np.ndarray:
    """Round masses, evenly spaced (1, 2, 2.5 or 5 times a power of ten), covering [low,
    high]: at most a dozen."""
    from irb140_dynamics.figures import round_steps

    return round_steps(low, high, 10)
