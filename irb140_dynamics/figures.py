"""Figures that read at a glance: what each plot of the package calls instead of
``tight_layout``, and the check its tests apply to every figure (matplotlib; imports
nothing of the package, serves every floor).

``fit_text`` wraps each text wider than the figure at spaces (a title naming a long path,
a label) and then lays the figure out tight; ``round_steps`` gives round, evenly spaced
values (contour levels, colour keys); ``label_curves`` labels contours upright where the
labels fit; ``clear_legend`` puts a legend inside its axes where it covers no data.
``figure_problems`` names what keeps a figure from reading well, which tests check is
nothing: narrower than MIN_WIDTH pixels as saved, no title, a text outside the figure
(``texts_outside``) or over another text, a text upside down, tick values that are not
round (evenly spaced by 1, 2, 2.5 or 5 times a power of ten, on a log axis each such a
multiple), a legend over plotted data (``legends_over_data``: a line, a marker, a bar or a
scatter point under it; a filled field such as a filled contour is a background, not
counted), a negative tick on an axis whose data are all >= 0 (a distance, a mass: the
view should start at 0).
"""

from __future__ import annotations

import math
import textwrap

MARGIN = 0.96  # of the figure's width a text may take
MIN_WIDTH = 1000  # px: the narrowest figure saved
ROUND = (1.0, 2.0, 2.5, 5.0)  # round steps, times a power of ten
OVERLAP = 1.0  # px: two texts' boxes may share this much each way (antialiasing)


def _texts(figure):
    """The texts drawn: visible, not empty, and not the labels of ticks outside the view
    (matplotlib keeps those, undrawn)."""
    from matplotlib.text import Text

    undrawn = set()
    for axes in figure.axes:
        for axis in (axes.xaxis, axes.yaxis):
            low, high = sorted(axis.get_view_interval())
            slack = 1e-9 * max(abs(low), abs(high), 1.0)
            for tick, location in zip(axis.get_major_ticks(), axis.get_majorticklocs()):
                if not low - slack <= location <= high + slack:
                    undrawn.update((id(tick.label1), id(tick.label2)))
    return [t for t in figure.findobj(Text) if t.get_visible() and t.get_text().strip() and id(t) not in undrawn]


def fit_text(figure, rect=(0.0, 0.0, 1.0, 1.0)) -> None:
    """Wrap every text that does not fit across the figure where it stands (a centred title
    may reach as far either side of its centre as the nearer edge allows), then
    ``tight_layout(rect=rect)``; again while the layout moved a text out (at most 3 times).
    The figure is left with no layout engine: tight_layout leaves a placeholder that lays
    nothing out but has ``savefig`` draw the whole figure once more before it draws it to
    save (a third of a plot's time; the same pixels)."""
    for _ in range(3):
        renderer = figure.canvas.get_renderer()
        wrapped = False
        for text in _texts(figure):
            wrapped |= _wrap(text, text.get_window_extent(renderer), MARGIN * figure.bbox.width)
        figure.tight_layout(rect=rect)
        figure.set_layout_engine(None)
        if not wrapped and not texts_outside(figure):
            return


def _wrap(text, extent, width: float) -> bool:
    """Wrap ``text`` (its extent in pixels) to what fits of ``width``; whether it was."""
    if text.get_rotation() % 180 != 0:  # an upright label: its height is the figure's business
        return False
    centre, margin = (extent.x0 + extent.x1) / 2, (1.0 - MARGIN) / 2 * width
    room = {
        "center": 2 * min(centre - margin, width + margin - centre),
        "left": width + margin - extent.x0,
        "right": extent.x1 - margin,
    }[text.get_horizontalalignment()]
    if extent.width <= room:
        return False
    lines = text.get_text().split("\n")
    columns = max(int(max(map(len, lines)) * max(room, 1.0) / extent.width) - 1, 10)
    text.set_text("\n".join(textwrap.fill(line, columns) for line in lines))
    return True


def texts_outside(figure) -> list[str]:
    """The texts (visible, not empty) whose tight bounding box is not inside the figure."""
    renderer = _drawn(figure)
    box, slack = figure.bbox, 0.5  # pixels: rounding
    outside = []
    for text in _texts(figure):
        extent = text.get_tightbbox(renderer)
        if extent is None:
            continue
        if (
            extent.x0 < box.x0 - slack
            or extent.y0 < box.y0 - slack
            or extent.x1 > box.x1 + slack
            or extent.y1 > box.y1 + slack
        ):
            outside.append(text.get_text())
    return outside


def round_steps(low: float, high: float, most: int = 10):
    """Round values covering [low, high]: evenly spaced by 1, 2, 2.5 or 5 times a power of
    ten, at most ``most`` + 1 of them (matplotlib's MaxNLocator)."""
    from matplotlib.ticker import MaxNLocator

    return MaxNLocator(most, steps=[1, 2, 2.5, 5, 10]).tick_values(low, high)


def figure_problems(figure, dpi=None) -> list[str]:
    """What keeps ``figure`` from reading well, saved at ``dpi`` (default: the figure's);
    see the module. An empty list: nothing."""
    renderer = _drawn(figure)
    problems = []
    width = figure.get_figwidth() * (dpi if isinstance(dpi, (int, float)) else figure.dpi)
    if width < MIN_WIDTH - 0.5:
        problems.append(f"{width:.0f} px wide, under {MIN_WIDTH}")
    texts = _texts(figure)
    titles = [figure.get_suptitle()] + [a.get_title(loc) for a in figure.axes for loc in ("left", "center", "right")]
    if not any(t.strip() for t in titles):
        problems.append("no title")
    problems += [f"outside the figure: {t!r}" for t in texts_outside(figure)]
    from matplotlib.text import Text

    boxes = [(t, Text.get_window_extent(t, renderer)) for t in texts]  # (an annotation's text, not its arrow)
    for text, box in boxes:
        clip = text.get_clip_box() if text.get_clip_on() else None
        if clip is not None and not _inside(box, clip):
            problems.append(f"cut by its axes: {text.get_text()!r}")
    for i, (a, box_a) in enumerate(boxes):
        for b, box_b in boxes[i + 1 :]:
            wide = min(box_a.x1, box_b.x1) - max(box_a.x0, box_b.x0)
            high = min(box_a.y1, box_b.y1) - max(box_a.y0, box_b.y0)
            if wide > OVERLAP and high > OVERLAP:
                problems.append(f"over each other: {a.get_text()!r} and {b.get_text()!r}")
    problems += [f"upside down: {t.get_text()!r}" for t in texts if 90 < t.get_rotation() % 360 < 270]
    problems += [f"legend over data: {name}" for name in legends_over_data(figure)]
    problems += negative_ticks(figure)
    for axes in figure.axes:
        for axis in (axes.xaxis, axes.yaxis):
            values = _labelled_ticks(axis)
            if not _round(values, axis.get_scale()):
                name = axes.get_title() or axes.get_label() or "axes"
                problems.append(f"ticks not round on {name} ({axis.axis_name}): {[float(f'{v:.6g}') for v in values]}")
    return problems


def _inside(box, frame, slack: float = 0.5) -> bool:
    return (
        box.x0 >= frame.x0 - slack
        and box.y0 >= frame.y0 - slack
        and box.x1 <= frame.x1 + slack
        and box.y1 <= frame.y1 + slack
    )


def _level_paths(curves) -> list:
    """One path per level of a ContourSet: its own since matplotlib 3.8; before (Ubuntu
    24.04's 3.6), the paths of each level's collection joined."""
    import matplotlib
    import numpy as np
    from matplotlib.path import Path

    if tuple(int(part) for part in matplotlib.__version__.split(".")[:2]) >= (3, 8):
        return list(curves.get_paths())
    return [
        Path.make_compound_path(*c.get_paths()) if c.get_paths() else Path(np.empty((0, 2))) for c in curves.collections
    ]


def label_curves(axes, curves, texts, **style) -> list:
    """Label each curve of ``curves`` (a ContourSet: one path per level) with its text of
    ``texts`` (None: no label), level, upright, on a light box where the curve lies
    farthest from the axes' edges and from the labels already placed; a curve with no
    such place gets none. Call after the layout (labels are placed in pixels). The labels."""
    import numpy as np

    figure = axes.figure
    renderer = _drawn(figure)
    frame = axes.get_window_extent(renderer)
    style = {"fontsize": 9, "ha": "center", "va": "center", "zorder": 6, **style}
    style.setdefault("bbox", dict(boxstyle="round,pad=0.15", facecolor="white", edgecolor="none", alpha=0.85))
    placed, boxes = [], [t.get_window_extent(renderer) for t in _texts(figure)]
    for path, text in zip(_level_paths(curves), texts):
        if text is None or len(path.vertices) == 0:
            continue
        points = axes.transData.transform(path.vertices)
        edge = np.min(
            np.abs(
                np.stack(
                    [points[:, 0] - frame.x0, frame.x1 - points[:, 0], points[:, 1] - frame.y0, frame.y1 - points[:, 1]]
                )
            ),
            axis=0,
        )
        for k in np.argsort(-edge)[:: max(1, len(points) // 60)]:
            label = axes.text(*path.vertices[k], text, **style)
            box = label.get_window_extent(renderer).padded(2)
            if _inside(box, frame) and not any(box.overlaps(other) for other in boxes):
                placed.append(label)
                boxes.append(box)
                break
            label.remove()
    return placed


def _labelled_ticks(axis) -> list[float]:
    """The values of the major ticks in view that show a label."""
    low, high = sorted(axis.get_view_interval())
    slack = 1e-9 * max(abs(low), abs(high), 1.0)
    return [
        float(location)
        for tick, location in zip(axis.get_major_ticks(), axis.get_majorticklocs())
        if low - slack <= location <= high + slack
        and any(label.get_visible() and label.get_text().strip() for label in (tick.label1, tick.label2))
    ]


def _round(values, scale: str) -> bool:
    """Are the values round: each a round multiple (log), or evenly spaced by a round step
    and multiples of it (linear; a single value: round itself)?"""
    if not values:
        return True
    if scale == "log" or len(values) == 1:
        return all(v == 0 or _round_number(abs(v)) for v in values)
    steps = [b - a for a, b in zip(values, values[1:])]
    step = steps[0]
    if step <= 0 or any(abs(s - step) > 1e-6 * step for s in steps) or not _round_number(step):
        return False
    return all(abs(v / step - round(v / step)) < 1e-6 for v in values)


def _round_number(x: float) -> bool:
    """Is x > 0 one of ROUND times a power of ten?"""
    if not (x > 0 and math.isfinite(x)):
        return False
    power = 10.0 ** math.floor(math.log10(x))
    mantissa = x / power
    return any(abs(mantissa - k) < 1e-6 * k or abs(mantissa - 10 * k) < 1e-5 * k for k in ROUND)


def _legends(figure) -> list:
    """The legends drawn: the figure's and each axes'."""
    legends = list(figure.legends) + [a.get_legend() for a in figure.axes if a.get_legend() is not None]
    return [legend for legend in legends if legend.get_visible()]


def legends_over_data(figure) -> list[str]:
    """The legends (each named by its entries) that cover plotted data of an axes where the
    axes show it: a line or a marker, a bar, a scatter point, a contour line."""
    renderer = _drawn(figure)
    return [
        repr(", ".join(t.get_text() for t in legend.get_texts()))
        for legend in _legends(figure)
        if _over_data(legend, figure, renderer)
    ]


def _over_data(legend, figure, renderer) -> bool:
    from matplotlib.transforms import Bbox

    box = legend.get_window_extent(renderer)
    for axes in figure.axes:
        if axes.get_label() == "<colorbar>":
            continue
        region = Bbox.intersection(box, axes.bbox)
        if region is None or region.width < 2 * OVERLAP or region.height < 2 * OVERLAP:
            continue
        if any(_covers(artist, region.padded(-OVERLAP), renderer) for artist in _data_of(axes)):
            return True
    return False


PLACES = ("best", "upper right", "upper left", "lower left", "lower right", "center right", "center left")


def clear_legend(axes, rect=(0.0, 0.0, 1.0, 1.0), **style):
    """The legend of ``axes`` at the first of PLACES where it covers no data (matplotlib's
    "best" only picks the place that covers least), else beside the axes, on the right, the
    figure laid out again (``fit_text`` with ``rect``). Call after the layout: the places
    are judged in pixels: the figure is drawn once (unless nothing changed since its last
    drawing), each place's legend found where its own drawing puts it, without drawing the
    figure again."""
    figure = axes.figure
    renderer = _drawn(figure)
    for place in PLACES:
        legend = axes.legend(loc=place, **style)
        if not _over_data(legend, figure, renderer):
            return legend
    legend = axes.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), **style)
    fit_text(figure, rect)
    return legend


def _drawn(figure):
    """The figure's renderer, the figure drawn as it stands: drawn now unless matplotlib
    marks nothing changed since its last drawing (``stale``, what interactive backends
    redraw by)."""
    if figure.stale:
        figure.draw_without_rendering()
    return figure.canvas.get_renderer()


def _data_of(axes) -> list:
    """The artists of ``axes`` that draw data (lines, patches such as bars, collections)."""
    return [a for a in (*axes.lines, *axes.patches, *axes.collections) if a.get_visible()]


def _covers(artist, region, renderer) -> bool:
    """Does ``artist`` draw inside ``region`` (a box in pixels)?"""
    import numpy as np
    from matplotlib.collections import Collection
    from matplotlib.lines import Line2D

    if isinstance(artist, Line2D):
        path = artist.get_transform().transform_path(artist.get_path())
        vertices = path.vertices[np.isfinite(path.vertices).all(axis=1)]
        if artist.get_marker() not in (None, "None", "none", "", " ") and _any_inside(
            vertices, region.padded(artist.get_markersize() * renderer.points_to_pixels(1.0) / 2)
        ):
            return True
        drawn = artist.get_linestyle() not in ("None", "none", "", " ") and artist.get_linewidth() > 0
        return drawn and _path_crosses(path, region)
    if isinstance(artist, Collection):
        if getattr(artist, "filled", False):  # a filled contour: a field under everything
            return False
        offsets, sizes = artist.get_offsets(), getattr(artist, "get_sizes", lambda: ())()
        if len(sizes) and len(offsets) and artist.get_offset_transform() is not None:  # a scatter
            points = artist.get_offset_transform().transform(np.asarray(offsets, dtype=float))
            size = float(np.sqrt(np.max(artist.get_sizes()))) * renderer.points_to_pixels(1.0) / 2
            return _any_inside(points[np.isfinite(points).all(axis=1)], region.padded(size))
        faces = np.asarray(artist.get_facecolor())
        if len(faces) and np.any(faces[:, 3] > 0):  # a filled area: a background
            return False
        transform = artist.get_transform()
        return any(_path_crosses(transform.transform_path(path), region) for path in artist.get_paths())
    extent = artist.get_window_extent(renderer)  # a patch: a bar
    return extent.width > 0 and extent.height > 0 and extent.overlaps(region)


def _any_inside(points, region) -> bool:
    import numpy as np

    x, y = points[:, 0], points[:, 1]
    return bool(np.any((x > region.x0) & (x < region.x1) & (y > region.y0) & (y < region.y1)))


def _path_crosses(path, region) -> bool:
    """Does the open path (pixels; NaNs break it) pass through ``region``?"""
    import numpy as np
    from matplotlib.path import Path

    vertices = path.vertices
    if len(vertices) == 0:
        return False
    finite = np.isfinite(vertices).all(axis=1)
    if finite.all():
        return path.intersects_bbox(region, filled=False) or _any_inside(vertices, region)
    return _any_inside(vertices[finite], region) or any(
        Path(vertices[k : k + 2]).intersects_bbox(region, filled=False)
        for k in np.flatnonzero(finite[:-1] & finite[1:])
    )


def negative_ticks(figure) -> list[str]:
    """An axis labelling negative values where every value drawn on it is >= 0: a
    distance, a mass, a share whose view should start at 0."""
    problems = []
    for axes in figure.axes:
        if axes.get_label() == "<colorbar>":
            continue
        limits = axes.dataLim
        for axis, low in ((axes.xaxis, limits.x0), (axes.yaxis, limits.y0)):
            if not (math.isfinite(low) and low >= 0.0) or axis.get_scale() != "linear":
                continue
            below = [float(f"{v:.6g}") for v in _labelled_ticks(axis) if v < 0.0]
            if below:
                name = axes.get_title() or axes.get_label() or "axes"
                problems.append(f"negative ticks {below} on {name} ({axis.axis_name}), its data all >= 0")
    return problems
