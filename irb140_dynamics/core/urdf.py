"""``irb140_dynamics.core.urdf``: the public name of the URDF reader and writer (core.io.urdf)."""

from irb140_dynamics.core.io.urdf import (
    CONTINUOUS_LIMITS,
    MAX_JOINTS,
    MAX_URDF_CHARS,
    LoadedUrdf,
    UrdfError,
    export_urdf,
    load_urdf,
    read_urdf,
)

__all__ = [
    "CONTINUOUS_LIMITS",
    "MAX_JOINTS",
    "MAX_URDF_CHARS",
    "LoadedUrdf",
    "UrdfError",
    "export_urdf",
    "load_urdf",
    "read_urdf",
]
