"""id_node and payload_check_node on one model and payload:
`ros2 launch irb140_dynamics id_and_payload_check.launch.py [params_file:=FILE] [payload_mass:=KG]`.

Launch arguments (all with defaults):
  params_file     the model's parameters (default: the installed config/irb140.yaml)
  payload_mass    kg, on the flange (default 0.0)
  payload_com     m, in the flange frame (default [0.0, 0.0, 0.0])
  rviz            true: start rviz2 with share/irb140_dynamics/rviz/dynamics.rviz (the
                  arm, TF, id_node's ~/markers; docs/visualization.md), where RViz is installed
                  (default false)
"""

from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue
from launch_ros.substitutions import FindPackageShare

from irb140_dynamics.ros.rviz_launch import rviz_entities
from launch import LaunchDescription

PACKAGE = "irb140_dynamics"


def generate_launch_description():
    shared = [
        LaunchConfiguration("params_file"),
        {
            "payload.mass": ParameterValue(LaunchConfiguration("payload_mass"), value_type=float),
            "payload.com": LaunchConfiguration("payload_com"),
        },
    ]
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "params_file",
                default_value=PathJoinSubstitution([FindPackageShare(PACKAGE), "config", "irb140.yaml"]),
                description="the model's parameters (YAML, as config/irb140.yaml)",
            ),
            DeclareLaunchArgument("payload_mass", default_value="0.0", description="payload mass [kg]"),
            DeclareLaunchArgument(
                "payload_com",
                default_value="[0.0, 0.0, 0.0]",
                description="payload centre of mass in the flange frame [m]",
            ),
            Node(package=PACKAGE, executable="id_node", name="id_node", output="screen", parameters=shared),
            Node(
                package=PACKAGE,
                executable="payload_check_node",
                name="payload_check_node",
                output="screen",
                parameters=shared,
            ),
            *rviz_entities(),
        ]
    )
