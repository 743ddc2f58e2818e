"""URDF text <-> RobotModel: ``load_urdf`` reads a chain of a URDF, ``export_urdf`` writes one.

Standard library XML only; meshes are never read. See docs/urdf.md.
"""

from irb140_dynamics.core.io.urdf.reader import CONTINUOUS_LIMITS, LoadedUrdf, load_urdf
from irb140_dynamics.core.io.urdf.tree import UrdfError
from irb140_dynamics.core.io.urdf.writer import export_urdf

__all__ = ["CONTINUOUS_LIMITS", "LoadedUrdf", "UrdfError", "export_urdf", "load_urdf"]
