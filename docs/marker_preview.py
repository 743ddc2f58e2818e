"""A preview of id_node's ~/markers drawn with matplotlib (not RViz): spheres, arrows, labels.

    python marker_preview.py markers.json markers_preview.png

``markers.json`` is a recorded visualization_msgs/MarkerArray, one object per marker with
the message's fields (ns, id, type, action, frame_id, position, scale, color, text,
points; see docs/visualization.md). Two views: from the side (x, z) and from above (x, y),
in the markers' frame, metres; the joints joined by a grey line to show the arm, their
labels in the side view only (from above, the stacked labels would overlap).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402

from irb140_dynamics.figures import fit_text  # noqa: E402

ARROW, SPHERE, TEXT = 0, 2, 9  # visualization_msgs/Marker types
ADD = 0
VIEWS = (("side view", 0, 2, "x [m]", "z [m]"), ("top view", 0, 1, "x [m]", "y [m]"))  # the joints' labels: side only


def draw(recording, out) -> None:
    """Draw the markers of ``recording`` (JSON) into the PNG ``out``."""
    markers = [m for m in json.loads(Path(recording).read_text()) if m["action"] == ADD]
    frame = markers[0]["frame_id"] if markers else "?"
    figure, axes = plt.subplots(1, 2, figsize=(12, 6))
    for axis, (title, a, b, xlabel, ylabel) in zip(axes, VIEWS):
        joints = sorted((m for m in markers if m["ns"] == "joint_load"), key=lambda m: m["id"])
        axis.plot([0.0] + [m["position"][a] for m in joints], [0.0] + [m["position"][b] for m in joints], color="0.6")
        for m in markers:
            colour = (*m["color"][:3], m["color"][3])
            x, y = m["position"][a], m["position"][b]
            if m["type"] == SPHERE:
                axis.add_patch(Circle((x, y), m["scale"][0] / 2, color=colour, zorder=3))
            elif m["type"] == ARROW:
                (x0, y0), (x1, y1) = ((p[a], p[b]) for p in m["points"])
                axis.annotate("", (x1, y1), (x0, y0), arrowprops=dict(color=colour, width=2, headwidth=8), zorder=4)
            elif m["type"] == TEXT and (m["ns"] != "joint_label" or b == 2):
                text_colour = "black" if m["color"][:3] == [1.0, 1.0, 1.0] else colour  # RViz's white: on white paper
                axis.text(x, y, m["text"], fontsize=7, color=text_colour, ha="center", va="bottom", zorder=5)
        axis.set_title(f"{title} of ~/markers in {frame}")
        axis.set_xlabel(xlabel)
        axis.set_ylabel(ylabel)
        axis.set_aspect("equal", adjustable="datalim")
        axis.autoscale_view()
        axis.margins(0.25)
        axis.grid(True, linewidth=0.3)
    fit_text(figure)
    figure.savefig(out, dpi=80)
    plt.close(figure)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit("usage: python marker_preview.py MARKERS.json OUT.png")
    draw(sys.argv[1], sys.argv[2])
    print(f"preview written: {sys.argv[2]}")
