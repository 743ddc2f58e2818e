"""A preview of id_node's ~/markers drawn with matplotlib (not RViz): spheres, arrows, labels.

    python marker_preview.py markers.json markers_preview.png

``markers.json`` is a recorded visualization_msgs/MarkerArray, one object per marker with
the message's fields (ns, id, type, action, frame_id, position, scale, color, text,
points; see docs/visualization.md). Two views: from above (x, y) and from the side (x, z),
in the markers' frame, metres; the joints joined by a grey line to show the arm. The texts
(each joint's load, the force, a collision) stand in a column beside the side view, each
joined to what it names, so that none hides another or a sphere; a colour bar keys the
joints' load colours and a legend the other markers.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402

from irb140_dynamics.core.monitoring import display  # noqa: E402
from irb140_dynamics.figures import fit_text  # noqa: E402

ARROW, SPHERE, TEXT = 0, 2, 9  # visualization_msgs/Marker types
ADD = 0
VIEWS = (("from above", 0, 1, "x [m]", "y [m]"), ("from the side", 0, 2, "x [m]", "z [m]"))
DPI = 100


def draw(recording, out) -> None:
    """Draw the markers of ``recording`` (JSON) into the PNG ``out``."""
    markers = [m for m in json.loads(Path(recording).read_text()) if m["action"] == ADD]
    frame = markers[0]["frame_id"] if markers else "?"
    figure, axes = plt.subplots(1, 2, figsize=(14, 7), dpi=DPI, gridspec_kw={"width_ratios": (1, 1)})
    joints = sorted((m for m in markers if m["ns"] == "joint_load"), key=lambda m: m["id"])
    for axis, (title, a, b, xlabel, ylabel) in zip(axes, VIEWS):
        axis.plot([0.0] + [m["position"][a] for m in joints], [0.0] + [m["position"][b] for m in joints], color="0.6")
        for m in markers:
            colour = (*m["color"][:3], m["color"][3])
            x, y = m["position"][a], m["position"][b]
            if m["type"] == SPHERE:
                axis.add_patch(Circle((x, y), m["scale"][0] / 2, color=colour, zorder=3))
            elif m["type"] == ARROW:
                (x0, y0), (x1, y1) = ((p[a], p[b]) for p in m["points"])
                axis.annotate("", (x1, y1), (x0, y0), arrowprops=dict(color=colour, width=2, headwidth=8), zorder=4)
        axis.set_title(f"{title} ({frame} frame)", fontsize=11)
        axis.set_xlabel(xlabel)
        axis.set_ylabel(ylabel)
        axis.set_aspect("equal", adjustable="datalim")
        axis.autoscale_view()
        axis.margins(0.15)
        axis.grid(True, linewidth=0.3)
    figure.suptitle(
        f"id_node's ~/markers of {Path(recording).name}: the joints coloured by their load, the payload, "
        "the force on the flange, a collision",
        fontsize=12,
    )
    _key(figure, axes)
    fit_text(figure, rect=(0.0, 0.0, 0.8, 1.0))  # the right fifth: the side view's texts
    _texts(axes[1], markers, joints)
    figure.savefig(out, dpi=DPI)
    plt.close(figure)


def _key(figure, axes) -> None:
    """The load colours as a colour bar under the view from above (display.load_colour, 0
    to 100 %), the other markers in a legend in it."""
    loads = np.linspace(0.0, 1.0, 256)
    scale = ListedColormap([display.load_colour(x) for x in loads])
    bar = figure.colorbar(
        plt.cm.ScalarMappable(plt.Normalize(0, 100), scale), ax=axes[0], location="bottom", shrink=0.8, pad=0.12
    )
    bar.set_label("joint load: |torque| / limit [%] (red from 100 %)")
    handles = [
        Line2D(
            [],
            [],
            marker="o",
            linestyle="",
            markersize=12,
            color=display.GREY,
            alpha=0.6,
            label="joint without a limit",
        ),
        Line2D(
            [], [], marker="o", linestyle="", markersize=12, color=(0.2, 0.4, 1.0), alpha=0.7, label="payload (its CoM)"
        ),
        Line2D([], [], color=(1.0, 0.0, 1.0), linewidth=2.5, label="force on the flange"),
        Line2D([], [], marker="$!$", linestyle="", markersize=10, color="red", label="collision (text)"),
    ]
    axes[0].legend(handles=handles, loc="upper left", fontsize=9, framealpha=0.9)


def _texts(axis, markers, joints) -> None:
    """Each text marker in a column right of ``axis``, top to bottom as their places are,
    a thin line to the marker it names (a joint's sphere, the arrow's tip, the flange)."""
    by_id = {m["id"]: m for m in joints}
    arrows = [m for m in markers if m["type"] == ARROW]
    items = []
    for m in markers:
        if m["type"] != TEXT:
            continue
        if m["ns"] == "joint_label" and m["id"] in by_id:
            target = by_id[m["id"]]["position"]
        elif m["ns"] == "external_force" and arrows:
            target = arrows[0]["points"][1]
        elif m["ns"] == "collision" and arrows:
            target = arrows[0]["points"][0]
        else:
            target = m["position"]
        colour = "black" if m["color"][:3] == [1.0, 1.0, 1.0] else tuple(m["color"][:3])  # RViz's white: on paper
        items.append((target[2], m["id"], m["text"], (target[0], target[2]), colour))
    items.sort(key=lambda item: (-item[0], item[1]))
    for k, (_, _, text, target, colour) in enumerate(items):
        slot = 1.0 - (k + 0.5) / max(len(items), 1)
        axis.annotate(
            text,
            target,
            xytext=(1.06, slot),
            textcoords="axes fraction",
            fontsize=10,
            color=colour,
            va="center",
            arrowprops=dict(arrowstyle="-", color="0.55", linewidth=0.7, shrinkA=2, shrinkB=4),
            annotation_clip=False,
        )


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit("usage: python marker_preview.py MARKERS.json OUT.png")
    draw(sys.argv[1], sys.argv[2])
    print(f"preview written: {sys.argv[2]}")
