"""A visualization_msgs/MarkerArray as the JSON docs/marker_preview.py reads: one object per
marker with its fields (positions, scales and colours as lists), numbers rounded to 1e-6."""

import json


def _round(values) -> list:
    return [round(float(x), 6) for x in values]


def marker_dicts(markers) -> list[dict]:
    return [
        {
            "ns": m.ns,
            "id": m.id,
            "type": m.type,
            "action": m.action,
            "frame_id": m.header.frame_id,
            "position": _round((m.pose.position.x, m.pose.position.y, m.pose.position.z)),
            "scale": _round((m.scale.x, m.scale.y, m.scale.z)),
            "color": _round((m.color.r, m.color.g, m.color.b, m.color.a)),
            "text": m.text,
            "points": [_round((p.x, p.y, p.z)) for p in m.points],
            "lifetime": round(m.lifetime.sec + m.lifetime.nanosec * 1e-9, 6),
        }
        for m in markers.markers
    ]


def marker_json(markers) -> str:
    return json.dumps(marker_dicts(markers), indent=1) + "\n"
