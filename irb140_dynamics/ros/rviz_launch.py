"""The ``rviz`` argument of every launch file of the package: ``rviz:=true`` starts rviz2 with
share/irb140_dynamics/rviz/dynamics.rviz (the arm, its TF and id_node's ~/markers; see
docs/visualization.md) where RViz is installed; where it is not, the launch says so and
starts the rest. Imported by the launch files only (``launch`` and ``launch_ros`` come with
ROS 2, not with this package's Python requirements).
"""

from __future__ import annotations

PACKAGE = "irb140_dynamics"
CONFIG = ("rviz", "dynamics.rviz")  # in the package's share directory
NOT_INSTALLED = "rviz:=true, but rviz2 is not installed (sudo apt install ros-jazzy-rviz2): starting without it"


def rviz_installed() -> bool:
    """Whether the ament index knows rviz2 (as ros2 launch looks a package up)."""
    try:
        from ament_index_python.packages import get_package_share_directory

        get_package_share_directory("rviz2")
    except (ImportError, LookupError, OSError):  # not found: a KeyError; no ament index at all: OSError
        return False
    return True


def rviz_entities() -> list:
    """The ``rviz`` launch argument (default false) and what it starts."""
    from launch.actions import DeclareLaunchArgument, LogInfo
    from launch.conditions import IfCondition
    from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
    from launch_ros.actions import Node
    from launch_ros.substitutions import FindPackageShare

    wanted = IfCondition(LaunchConfiguration("rviz"))
    argument = DeclareLaunchArgument(
        "rviz", default_value="false", description="true: start rviz2 with the package's config (where installed)"
    )
    if not rviz_installed():
        return [argument, LogInfo(msg=NOT_INSTALLED, condition=wanted)]
    config = PathJoinSubstitution([FindPackageShare(PACKAGE), *CONFIG])
    rviz = Node(
        package="rviz2", executable="rviz2", name="rviz2", output="screen", arguments=["-d", config], condition=wanted
    )
    return [argument, rviz]
