"""Launch several clew_planner nodes, each in its own namespace with its own world.

ros2 launch clew_ros clew_planners.launch.py planners:="arm_a:=/path/a.yaml arm_b:=/path/b.yaml"
ros2 launch clew_ros clew_planners.launch.py record_directory:=~/runs   # the four demo worlds of config/

planners: space-separated NAMESPACE:=WORLD.yaml pairs, one node /NAMESPACE/clew_planner per pair serving
the world file (whatever its node key; clew_ros.node.namespaces reads it as clew_plan does). Empty: figure1,
arm3_regrasp, arm5_regrasp and single_transfer of the installed config/, each in a namespace of its name.
Each node records into <record directory>/<NAMESPACE>/ and publishes its TF into its namespace
(/NAMESPACE/tf, /NAMESPACE/tf_static). One process in all: `clew_planners` (clew_ros/node/multi.py).
"""

from pathlib import Path

from ament_index_python.packages import get_package_share_directory
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from clew_ros.node.namespaces import TF_REMAPPINGS, demo_pairs, launch_parameters, parse_planner_pairs
from launch import LaunchDescription


def planner_nodes(context, *args, **kwargs):
    """One clew_planner Node per NAMESPACE:=WORLD.yaml pair of the planners argument."""
    del args, kwargs
    pairs = LaunchConfiguration("planners").perform(context).split()
    if not pairs:
        pairs = demo_pairs(Path(get_package_share_directory("clew_ros")) / "config")
    record_directory = LaunchConfiguration("record_directory").perform(context)
    return [
        Node(
            package="clew_ros",
            executable="clew_planner",
            name="clew_planner",
            namespace=spec.namespace,
            output="screen",
            parameters=[launch_parameters(spec, record_directory)],
            remappings=list(TF_REMAPPINGS),
        )
        for spec in parse_planner_pairs(pairs)
    ]


def generate_launch_description() -> LaunchDescription:
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "planners",
                default_value="",
                description="space-separated NAMESPACE:=WORLD.yaml pairs, one clew_planner each "
                "(empty: figure1, arm3_regrasp, arm5_regrasp and single_transfer of config/)",
            ),
            DeclareLaunchArgument(
                "record_directory",
                default_value="",
                description="each planner records into <this>/<NAMESPACE>/ (empty: the world file's "
                "record.directory, else ~/.ros/clew_recordings)",
            ),
            OpaqueFunction(function=planner_nodes),
        ]
    )
