"""Build script for clew_ros (ament_python: colcon and pip both use it)."""

from glob import glob
from pathlib import Path

from setuptools import find_packages, setup

package_name = "clew_ros"


def robot_files() -> list[tuple[str, list[str]]]:
    """config/robots/<name>/... (URDF, SRDF, collision meshes, licences), installed folder by folder."""
    files = sorted(p for p in glob("config/robots/**/*", recursive=True) if Path(p).is_file())
    folders = sorted({str(Path(p).parent) for p in files})
    return [("share/" + package_name + "/" + d, [p for p in files if str(Path(p).parent) == d]) for d in folders]


setup(
    name=package_name,
    version="0.1.0",
    description=("Manipulation planning with the Ariadne's Clew Algorithm, served as a ROS 2 node."),
    maintainer="clew_ros maintainers",
    maintainer_email="clew-ros@example.com",
    license="Apache-2.0",
    packages=find_packages(exclude=["test", "test.*", "benchmarks", "benchmarks.*"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + package_name]),
        ("share/" + package_name, ["package.xml"]),
        (
            "share/" + package_name + "/config",
            sorted(glob("config/*.yaml") + glob("config/*.json")),
        ),
        *robot_files(),
        # the spatial example worlds, their witness plans and the MoveIt scene one of them reads (docs/spatial.md)
        (
            "share/" + package_name + "/config/spatial",
            sorted(glob("config/spatial/*.yaml") + glob("config/spatial/*.json")),
        ),
        ("share/" + package_name + "/launch", sorted(glob("launch/*.py"))),
        # the SROS2 policy of the node (docs/security.md)
        ("share/" + package_name + "/config/sros2", sorted(glob("config/sros2/*.xml"))),
    ],
    python_requires=">=3.11",
    install_requires=[
        "numpy>=1.26",
        "numba>=0.59",  # the compiled planning kernels (clew_ros/planar/kernel/)
        "shapely>=2.1",
        "pyyaml>=6.0",
        "mcap>=1.2",
        "mcap-ros2-support>=0.5",
        # recordings: the CDR and the definitions of the recorded messages, tf2_msgs among them (recording/cdr.py)
        "rosbags>=0.10",
        # what mcap decompresses chunks with; the reader decompresses them itself, bounded (recording/reader.py)
        "zstandard>=0.22",
        "lz4>=4.0",
        "pillow>=10.0",
        # spatial worlds: the URDF parser, collision meshes (STL, OBJ; DAE through pycollada) and coal, the
        # collision library that decides validity on the URDF's exact geometry (clew_ros/spatial/tier.py)
        "urdf-parser-py>=0.0.4",
        "trimesh>=4.0",
        "pycollada>=0.8",
        "coal>=3.0",
    ],
    extras_require={
        # ROS 2 Jazzy from PyPI wheels; a native install uses the distro's instead.
        "ros": [
            "ros-jazzy-rclpy[fastrtps]>=7.1",
            "ros-jazzy-common-interfaces>=5.3",
            "ros-jazzy-std-srvs>=5.3",
        ],
        # test: lxml (test/security/test_deploy_policy.py validates the SROS2 policy as sros2 does: XSD, XSLT),
        # the spatial packages (test/spatial loads the shipped robots' URDFs and meshes) and pinocchio (the
        # exact reference the two-tier checker is tested against)
        "test": [
            "pytest>=8.0",
            "hypothesis>=6.100",
            "urdf-parser-py>=0.0.4",
            "lxml>=5.0",
            "trimesh>=4.0",
            "pycollada>=0.8",
            "pin>=3.0",
        ],
        # python -m benchmarks.run (docs/benchmarks.md); the profile uses the standard library's cProfile.
        # roboplan-rrt: the exact-geometry C++ RRT-Connect peer of `python -m benchmarks spatial_motion` (it
        # brings pin and coal, as the spatial-ref extra does).
        "bench": ["ompl>=2.0", "matplotlib>=3.8", "roboplan-rrt>=0.7"],
        # clew_plan --foxglove (clew_ros/live): the run served live to Foxglove over a WebSocket on 127.0.0.1.
        # websockets and protobuf are the tests' client (test/helpers/foxglove_client.py): it subscribes and
        # decodes with the schemas the server advertises, as the Foxglove app does.
        "live": ["foxglove-sdk>=0.30.3", "websockets>=15.0", "protobuf>=5.29"],
        # clew_batch --ray (clew_ros/batch/executors.py): jobs as Ray tasks, on a local Ray or a cluster.
        "batch": ["ray>=2.9"],
        # clew_ros.spatial (spatial worlds): what install_requires brings; kept so that `.[spatial]` still works.
        "spatial": ["urdf-parser-py>=0.0.4", "trimesh>=4.0", "pycollada>=0.8", "coal>=3.0"],
        # clew_ros.spatial.exact (spatial_families --exact, the tests' reference): pinocchio's own kinematics
        # with coal, independent of the planner's.
        "spatial-ref": ["pin>=3.0", "coal>=3.0"],
        # make lint (and .ci/run): the checks configured in pyproject.toml. ruff's minor is capped: a new
        # minor release turns on new rules of the selected families, which would fail CI with no code change.
        # foxglove-sdk too: mypy reads its own type information for clew_ros/live.
        "lint": ["ruff>=0.17.6,<0.18", "mypy>=2.4", "types-PyYAML>=6.0", "types-shapely>=2.1", "foxglove-sdk>=0.30.3"],
    },
    zip_safe=True,
    entry_points={
        "console_scripts": [
            "clew_planner = clew_ros.node.main:main",
            "clew_planners = clew_ros.node.multi:main",
            "clew_plan = clew_ros.cli.plan:main",
            "clew_replay = clew_ros.cli.replay:main",
            "clew_render = clew_ros.cli.render:main",
            "clew_batch = clew_ros.cli.batch:main",
            "clew_world = clew_ros.cli.world:main",
        ],
    },
)
