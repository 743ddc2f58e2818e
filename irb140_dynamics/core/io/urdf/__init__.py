"""URDF text <-> RobotModel: ``load_urdf`` reads a chain of a URDF, ``export_urdf`` writes one.

Standard library XML only; meshes are never read. See docs/urdf.md.
"""

from irb140_dynamics.core.io.urdf.reader import CONTINUOUS_LIMITS, MAX_JOINTS, LoadedUrdf, load_urdf, read_urdf
from irb140_dynamics.core.io.urdf.tree import MAX_URDF_CHARS, UrdfError
from irb140_dynamics.core.io.urdf.writer import export_urdf

__all__ = [
    "CONTINUOUS_LIMITS",
    "LoadedUrdf",
    "MAX_JOINTS",
    "MAX_URDF_CHARS",
    "UrdfError",
    "export_urdf",
    "load_urdf",
    "read_urdf",
]
