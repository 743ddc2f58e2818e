"""Numbers and values as YAML text that every reader types right.

A double always has a decimal point or an exponent with one (``0.0``, ``1.5e-05``): rcl's
parameter parser would take ``0`` for an integer, and PyYAML (``ros2 topic pub``) takes
``1e-05`` for a string.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np


def yaml_float(x: float, digits: int | None = None) -> str:
    """A double as YAML that parses back as that double (17 significant digits by default)."""
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"cannot write the non-finite number {x}")
    text = repr(x) if digits is None else f"{x:.{digits}g}"
    mantissa, _, exponent = text.partition("e")
    if "." not in mantissa:
        mantissa += ".0"
    return mantissa + (f"e{exponent}" if exponent else "")


def yaml_value(value: Any) -> str:
    if isinstance(value, str):
        return json.dumps(value)  # a double-quoted YAML string
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(yaml_value(v) for v in value) + "]"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    return yaml_float(value)
