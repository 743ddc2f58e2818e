"""Where the package's files are: installed (ament index), else in the source tree. No ROS needed."""

from __future__ import annotations

from pathlib import Path

PACKAGE = "irb140_dynamics"
CONFIG_NAME = "irb140.yaml"


def default_config_path() -> Path:
    """The installed config/irb140.yaml (where ros2 run finds it), else the source tree's."""
    try:
        from ament_index_python.packages import get_package_share_directory

        return Path(get_package_share_directory(PACKAGE)) / "config" / CONFIG_NAME
    except (ImportError, LookupError, OSError):  # not installed, or no AMENT_PREFIX_PATH
        return Path(__file__).resolve().parents[1] / "config" / CONFIG_NAME
