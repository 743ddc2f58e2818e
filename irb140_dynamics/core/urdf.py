"""``irb140_dynamics.core.urdf``: the public name of the URDF reader and writer (core.io.urdf)."""

from irb140_dynamics.core.io.urdf import CONTINUOUS_LIMITS, LoadedUrdf, UrdfError, export_urdf, load_urdf

__all__ = ["CONTINUOUS_LIMITS", "LoadedUrdf", "UrdfError", "export_urdf", "load_urdf"]
