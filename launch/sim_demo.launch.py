"""The simulated closed loop of `./scripts/run.sh --demo`: sim_node (a 'true' IRB-140 that
differs from the model, config/true_arm.yaml), id_node in computed-torque mode on the
report's model, and demo_node sending it a reference motion and printing the tracking error:
`ros2 launch irb140_dynamics sim_demo.launch.py [plot_file:=PNG] [duration:=S]`.

Launch arguments (all with defaults):
  true_arm_file   the simulated arm's parameters (default: the installed config/true_arm.yaml)
  params_file     id_node's model (default: the installed config/irb140.yaml)
  plot_file       where demo_node writes its plot at the end (default demo_tracking.png,
                  in the directory ros2 launch was started from)
  duration        s, demo_node stops this long after its first figures; 0 = until Ctrl-C (default 0.0)
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
START = [0.0, -0.6, 1.0, 0.0, 0.5, 0.0]  # rad: where demo_node's motion starts and ends


def generate_launch_description():
    share = FindPackageShare(PACKAGE)
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "true_arm_file",
                default_value=PathJoinSubstitution([share, "config", "true_arm.yaml"]),
                description="the simulated arm's parameters",
            ),
            DeclareLaunchArgument(
                "params_file",
                default_value=PathJoinSubstitution([share, "config", "irb140.yaml"]),
                description="id_node's model",
            ),
            DeclareLaunchArgument(
                "plot_file", default_value="demo_tracking.png", description="demo_node's plot, written at the end"
            ),
            DeclareLaunchArgument("duration", default_value="0.0", description="s; 0 = until Ctrl-C"),
            Node(
                package=PACKAGE,
                executable="sim_node",
                name="sim_node",
                output="screen",
                parameters=[LaunchConfiguration("true_arm_file"), {"initial_positions": START}],
            ),
            Node(
                package=PACKAGE,
                executable="id_node",
                name="id_node",
                output="screen",
                parameters=[
                    LaunchConfiguration("params_file"),
                    {"effort_commands.enabled": True, "effort_commands.source": "computed_torque"},
                ],
            ),
            Node(
                package=PACKAGE,
                executable="demo_node",
                name="demo_node",
                output="screen",
                parameters=[
                    {
                        "plot_file": LaunchConfiguration("plot_file"),
                        "duration": ParameterValue(LaunchConfiguration("duration"), value_type=float),
                    }
                ],
            ),
            *rviz_entities(),
        ]
    )
