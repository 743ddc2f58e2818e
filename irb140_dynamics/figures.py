"""Figures whose every title and label shows whole: what each plot of the package calls
instead of ``tight_layout`` (matplotlib; imports nothing of the package, serves every floor).

``fit_text`` wraps each text wider than the figure at spaces (a title naming a long path,
a label) and then lays the figure out tight; ``texts_outside`` names the texts whose tight
bounding box leaves the figure's, which tests check is none.
"""

from __future__ import annotations

import textwrap

MARGIN = 0.96  # of the figure's width a text may take


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
    ``tight_layout(rect=rect)``; again while the layout moved a text out (at most 3 times)."""
    for _ in range(3):
        renderer = figure.canvas.get_renderer()
        wrapped = False
        for text in _texts(figure):
            wrapped |= _wrap(text, text.get_window_extent(renderer), MARGIN * figure.bbox.width)
        figure.tight_layout(rect=rect)
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
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
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
