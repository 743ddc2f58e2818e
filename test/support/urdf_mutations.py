"""Hostile URDF text for the fuzz test of ``load_urdf`` and its longer run in bench/: a
valid chain mutated by a few random edits (attribute values made absurd, elements
duplicated or cut, types changed, bytes inserted, the text truncated).

``outcome`` runs the loader on one text and says what became of it: "loaded" (the model
computes finite torques), "refused" (UrdfError in one line under 300 characters), or a
"defect: ..." line."""

from __future__ import annotations

import math
import re

import numpy as np

from irb140_dynamics.core import gravity, mass_matrix, rnea
from irb140_dynamics.core.urdf import UrdfError, load_urdf

LIMIT = '<limit lower="-1" upper="1" effort="10" velocity="1"/>'
INERTIAL = '<inertial><origin xyz="0.1 0 0" rpy="0 1.5707963 0"/><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1"/></inertial>'
SEED_TEXT = f"""<robot name="arm">
  <link name="world"/>
  <joint name="mount" type="fixed"><parent link="world"/><child link="base"/><origin rpy="1.5707963 0 0"/></joint>
  <link name="base">{INERTIAL}</link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>{LIMIT}</joint>
  <link name="l1">{INERTIAL}</link>
  <joint name="slide-2" type="prismatic"><parent link="l1"/><child link="l2"/><origin xyz="0.3 0 0" rpy="0 0 0.5"/><axis xyz="0 1 0"/>{LIMIT}<dynamics damping="0.1" friction="0.2"/></joint>
  <link name="l2">{INERTIAL}</link>
  <joint name="j3" type="continuous"><parent link="l2"/><child link="l3"/><origin xyz="0 0.2 0"/><axis xyz="1 0 0"/></joint>
  <link name="l3">{INERTIAL}</link>
  <joint name="finger" type="prismatic"><parent link="l3"/><child link="f"/><axis xyz="0 1 0"/>{LIMIT}<mimic joint="j3"/></joint>
  <link name="f">{INERTIAL}</link>
  <joint name="tool" type="fixed"><parent link="l3"/><child link="tool0"/><origin xyz="0 0 0.05"/></joint>
  <link name="tool0"/>
</robot>"""
VALUES = (
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-320",
    "-1",
    "0",
    "",
    "1 2",
    "abc",
    "0x10",
    "1e6 1e6 1e6",
    "3.14159265358979 0 0",
    "-0.5 0.5 -0.5",
    "\u00e9",
    "a" * 400,
    "1" * 400,
    "0 0 0",
    "&amp;",
    "link",
    "l1",
)
TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar", "ball", "")
SNIPPETS = (
    "\x00",
    "\x01",
    "\ufffd",
    "<",
    ">",
    "</joint>",
    '<link name="l1"/>',
    "<robot>",
    "]]>",
    "<!--",
    "&lol;",
    '<joint name="j1" type="fixed"><parent link="l3"/><child link="base"/></joint>',
    '<joint name="x" type="revolute"><parent link="tool0"/><child link="l1"/></joint>',
    '<mimic joint="j1"/>',
)
KINDS = ("value", "type", "duplicate", "delete", "insert", "truncate", "rename")
_ATTRIBUTE = re.compile(r'="[^"]*"')
_ELEMENT = re.compile(r"<(link|joint)\b.*?(?:/>|</\1>)", re.S)


def mutated(text: str, edits) -> str:
    """``text`` after ``edits``: (kind, where in [0, 1), which: int) each."""
    for kind, where, which in edits:
        if kind == "value":
            spans = list(_ATTRIBUTE.finditer(text))
            if spans:
                span = spans[int(where * len(spans))]
                text = f'{text[: span.start()]}="{VALUES[which % len(VALUES)]}"{text[span.end() :]}'
        elif kind == "type":
            spans = list(re.finditer(r'type="[^"]*"', text))
            if spans:
                span = spans[int(where * len(spans))]
                text = f'{text[: span.start()]}type="{TYPES[which % len(TYPES)]}"{text[span.end() :]}'
        elif kind in ("duplicate", "delete"):
            spans = list(_ELEMENT.finditer(text))
            if spans:
                span = spans[int(where * len(spans))]
                element = span.group() * (which % 3 + 1) if kind == "duplicate" else ""
                text = text[: span.start()] + element + text[span.end() :]
        elif kind == "insert":
            at = int(where * len(text))
            text = text[:at] + SNIPPETS[which % len(SNIPPETS)] + text[at:]
        elif kind == "truncate":
            text = text[: int(where * len(text))]
        elif kind == "rename":
            names = sorted(set(re.findall(r'name="([^"]*)"', text)))
            if names:
                old = names[int(where * len(names))]
                text = text.replace(f'"{old}"', f'"{VALUES[which % len(VALUES)]}"')
    return text


def outcome(text: str, ends: dict | None = None) -> str:
    """ "loaded", "refused", or "defect: <what>" (see the module)."""
    try:
        loaded = load_urdf(text, **(ends or {}))
    except UrdfError as error:
        line = str(error)
        if "\n" in line or len(line) >= 300:
            return f"defect: a refusal of {len(line)} characters over {line.count(chr(10)) + 1} lines"
        return "refused"
    except Exception as error:  # what the test looks for
        return f"defect: {type(error).__name__}: {str(error)[:200]}"
    model = loaded.model
    zeros, ones = [0.0] * model.n, [0.5] * model.n
    try:
        values = [rnea(model, ones, ones, ones), gravity(model, zeros), mass_matrix(model, ones)]
    except Exception as error:
        return f"defect: loaded, then {type(error).__name__}: {str(error)[:200]}"
    if not all(math.isfinite(x) for v in values for x in np.ravel(v)):
        return "defect: loaded, then non-finite torques"
    return "loaded"
