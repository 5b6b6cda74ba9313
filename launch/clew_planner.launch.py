"""Launch the clew_planner node, optionally with a parameter file.

ros2 launch clew_ros clew_planner.launch.py params_file:=/path/to/world.yaml

params_file is only compared with '' (EqualsSubstitution / NotEqualsSubstitution,
plain string comparisons) and handed to the node as a path: it is never
evaluated, so a path with quotes or any other text in it is taken as it is.
"""

from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import EqualsSubstitution, LaunchConfiguration, NotEqualsSubstitution
from launch_ros.actions import Node

from launch import LaunchDescription


def generate_launch_description() -> LaunchDescription:
    params_file = LaunchConfiguration("params_file")
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
                condition=IfCondition(NotEqualsSubstitution(params_file, "")),
            ),
            Node(
                package="clew_ros",
                executable="clew_planner",
                name="clew_planner",
                output="screen",
                condition=IfCondition(EqualsSubstitution(params_file, "")),
            ),
        ]
    )
