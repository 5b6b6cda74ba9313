"""Launch clew_planner on a spatial world (interface.md section 1b): the shipped Panda and a scene.

ros2 launch clew_ros clew_spatial_planner.launch.py                        # the Panda, table to table
ros2 launch clew_ros clew_spatial_planner.launch.py world:=/path/to/my_arm_world.yaml record_directory:=~/runs

world: a spatial world file (default: config/spatial/panda_table_to_table.yaml of the installed package).
The files it names (world.robot.urdf, world.robot.srdf, world.scene_file) are read relative to its folder,
as clew_plan reads them (the node itself reads relative paths from its working directory), so the world
plans the same here and offline. record_directory: where runs are recorded (empty: the world file's
record.directory, else ~/.ros/clew_recordings).
"""

from pathlib import Path

from ament_index_python.packages import get_package_share_directory
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from clew_ros.ros.spatial import resolved_parameters
from launch import LaunchDescription

DEFAULT_WORLD = Path("config") / "spatial" / "panda_table_to_table.yaml"


def spatial_planner(context, *args, **kwargs):
    """The clew_planner Node of the world argument, its file paths made absolute."""
    del args, kwargs
    world = LaunchConfiguration("world").perform(context)
    path = Path(world) if world else Path(get_package_share_directory("clew_ros")) / DEFAULT_WORLD
    parameters = resolved_parameters(path.expanduser())
    record_directory = LaunchConfiguration("record_directory").perform(context)
    if record_directory:
        parameters = {**parameters, "record": {**parameters.get("record", {}), "directory": record_directory}}
    return [
        Node(
            package="clew_ros",
            executable="clew_planner",
            name="clew_planner",
            output="screen",
            parameters=[parameters],
        )
    ]


def generate_launch_description() -> LaunchDescription:
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "world",
                default_value="",
                description="a spatial world file (empty: config/spatial/panda_table_to_table.yaml, the Panda)",
            ),
            DeclareLaunchArgument(
                "record_directory",
                default_value="",
                description="where runs are recorded (empty: the world file's record.directory, else "
                "~/.ros/clew_recordings)",
            ),
            OpaqueFunction(function=spatial_planner),
        ]
    )
