"""Launch the clew_planner node, optionally with a parameter file.

ros2 launch clew_ros clew_planner.launch.py params_file:=/path/to/world.yaml
"""

from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition, UnlessCondition
from launch.substitutions import LaunchConfiguration, PythonExpression
from launch_ros.actions import Node

from launch import LaunchDescription


def generate_launch_description() -> LaunchDescription:
    params_file = LaunchConfiguration("params_file")
    has_params = PythonExpression(["'", params_file, "' != ''"])
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "params_file",
                default_value="",
                description="ROS 2 parameter YAML for clew_planner (empty: node defaults)",
            ),
            Node(
                package="clew_ros",
                executable="clew_planner",
                name="clew_planner",
                output="screen",
                parameters=[params_file],
                condition=IfCondition(has_params),
            ),
            Node(
                package="clew_ros",
                executable="clew_planner",
                name="clew_planner",
                output="screen",
                condition=UnlessCondition(has_params),
            ),
        ]
    )
