"""The node's own parameters: ``live.*``, ``parameters.*``, ``record.*``, ``markers.*`` and ``state.*``, with the
playback's timing (:data:`~clew_ros.core.parameters.PLAYBACK_PARAMETERS`) in :data:`NODE_PARAMETERS`; its switches
(:data:`RUNTIME_CHANGES`, :data:`SIM_TIME_CHANGES`, :data:`PLANNER_LOCK`) and the namespaces it fixes at start
(:data:`LOCKED_PREFIXES`).

Specified as the core's parameters are (:class:`~clew_ros.core.parameters.ParameterSpec`); they mean nothing
offline, so they live with the node's settings (:mod:`clew_ros.ros.parameters`) rather than in the core. The ROS
descriptors and the node table of docs/parameters.md are derived from them.
"""

from __future__ import annotations

from clew_ros.core.parameters import (
    KIND_PARAMETER,
    OBSTACLE_PARAMETER,
    PLANNER_PARAMETERS,
    PLAYBACK_PARAMETERS,
    WORLD_PARAMETERS,
    ParameterSpec,
    ParameterTable,
    ParameterType,
)
from clew_ros.spatial.parameters import SPATIAL_OBSTACLE_PARAMETERS, SPATIAL_WORLD_PARAMETERS

__all__ = [
    "LOCKED_PREFIXES",
    "NODE_PARAMETERS",
    "PLANNER_LOCK",
    "RUNTIME_CHANGES",
    "SIM_TIME_CHANGES",
    "STATE_PARAMETERS",
]

#: The name of the development switch: ``true`` lets the :attr:`~clew_ros.core.parameters.ParameterSpec.locked`
#: parameters change while the node runs.
RUNTIME_CHANGES = "parameters.allow_runtime_changes"
#: The switch that lets ``use_sim_time`` (the ROS client library's) change while the node runs (off: fixed at
#: its start value).
SIM_TIME_CHANGES = "parameters.allow_sim_time_changes"
#: The switch that fixes every ``planner.*`` parameter at start.
PLANNER_LOCK = "parameters.lock_planner"
#: The namespaces whose parameters are :attr:`~clew_ros.core.parameters.ParameterSpec.locked` (fixed at start):
#: the world (the robot, its limits, the obstacles), the trajectory limits a controller follows, where and
#: whether runs are recorded, the live view. A parameter under them that was not declared at start cannot be
#: added later.
LOCKED_PREFIXES = ("world.", "record.", "trajectory.", "live.")

_B, _I, _D, _S = ParameterType.BOOL, ParameterType.INTEGER, ParameterType.DOUBLE, ParameterType.STRING

STATE_PARAMETERS = [
    ParameterSpec(
        "state.joint_states",
        _B,
        False,
        "Plan each run from the latest joint_states (sensor_msgs/JointState, a relative name: /joint_states "
        "unless remapped): the planned joints by name (the fixed joints too when the message has them). "
        "Read only.",
        read_only=True,
    ),
    ParameterSpec(
        "state.max_age",
        _D,
        1.0,
        "With state.joint_states: a run asked while a planned joint has no state, or its latest is older than "
        "this by the node's clock (header stamp; the receive time when the stamp is zero), is refused "
        "START_STATE_UNKNOWN (10). Read only.",
        "s",
        (0.001, 3600.0),
        read_only=True,
    ),
    ParameterSpec(
        "state.object_pose",
        _B,
        False,
        "Start each run with the object at the latest ~/object (geometry_msgs/PoseStamped, frame world), "
        "snapped onto the nearest stable placement within state.snap_m and state.snap_rad, else refused "
        "INVALID_WORLD saying why. Read only.",
        read_only=True,
    ),
    ParameterSpec(
        "state.snap_m",
        _D,
        0.01,
        "How far (m) an ~/object pose's resting face may lie from a support's top face and still be snapped "
        "onto it. Read only.",
        "m",
        (0.0, 1.0),
        read_only=True,
    ),
    ParameterSpec(
        "state.snap_rad",
        _D,
        0.05,
        "How far (rad) an ~/object pose's resting face may be tilted from level and still be snapped level. Read only.",
        "rad",
        (0.0, 1.0),
        read_only=True,
    ),
    ParameterSpec(
        "state.obstacles",
        _B,
        False,
        "Obstacles added at run time from ~/obstacles (visualization_msgs/MarkerArray: CUBE, SPHERE, "
        "CYLINDER; ADD/MODIFY, DELETE, DELETEALL), named <ns>/<id>. Read only.",
        read_only=True,
    ),
    ParameterSpec(
        "state.points",
        _B,
        False,
        "Sensed obstacles from ~/points (sensor_msgs/PointCloud2, float32 x y z, frame world): each message "
        "replaces the previous cloud; points on the arm or the object are dropped, the rest occupy cubes of "
        "edge state.voxel_m, each a box obstacle points/<i>. Read only.",
        read_only=True,
    ),
    ParameterSpec(
        "state.voxel_m",
        _D,
        0.02,
        "Edge (m) of the cubes a point cloud occupies. Read only.",
        "m",
        (0.001, 1.0),
        read_only=True,
    ),
    ParameterSpec(
        "state.self_filter_m",
        _D,
        0.02,
        "Points within this distance (m) of the arm's links (their sphere cover) or of the object are dropped "
        "from a cloud. Read only.",
        "m",
        (0.0, 1.0),
        read_only=True,
    ),
    ParameterSpec(
        "state.max_points",
        _I,
        1_000_000,
        "Most points one ~/points message may hold; a larger one is refused with one warning and the previous "
        "cloud stays. Read only.",
        "points",
        (1, 100_000_000),
        read_only=True,
    ),
    ParameterSpec(
        "state.advance",
        _B,
        False,
        "After a run that succeeds, the next starts where its plan ended (the arm at its last waypoint, the "
        "object at its final pose) unless joint_states or ~/object say otherwise. Read only.",
        read_only=True,
    ),
]

NODE_PARAMETERS = ParameterTable(
    "",
    [
        ParameterSpec(
            "live.foxglove_port",
            _I,
            0,
            "Serve the runs live to Foxglove over a WebSocket on 127.0.0.1 at this port (0: off; needs the live "
            "extra, foxglove-sdk). Read only: taken when the node starts.",
            "",
            (0, 65535),
            read_only=True,
            locked=True,
        ),
        ParameterSpec(
            RUNTIME_CHANGES,
            _B,
            False,
            "Development switch: true lets ros2 param set change the world.*, record.*, trajectory.* and live.* "
            "parameters while the node runs (when no plan runs); false fixes them at start, and a change is "
            "refused naming the parameter. Read only: taken when the node starts.",
            read_only=True,
        ),
        ParameterSpec(
            SIM_TIME_CHANGES,
            _B,
            False,
            "true lets ros2 param set change use_sim_time while the node runs; false fixes it at its start value "
            "(a peer that switched it on would stamp ~/trajectory with its own /clock), and a change is refused "
            "naming it. Read only: taken when the node starts.",
            read_only=True,
        ),
        ParameterSpec(
            PLANNER_LOCK,
            _B,
            False,
            "true fixes every planner.* parameter at its start value (a change is refused naming it), so that no "
            "peer can change how much CPU a run takes or which plan a seed gives; false: planner.* settable. "
            "Read only: taken when the node starts.",
            read_only=True,
        ),
        ParameterSpec(
            "record.enabled",
            _B,
            True,
            "Record every run as a rosbag2 directory <record.directory>/<run id>/ (folders mode 0700, files 0600).",
            locked=True,
        ),
        ParameterSpec(
            "record.directory",
            _S,
            "~/.ros/clew_recordings",
            "Where runs are recorded, resolved once at start to an absolute path: '~' is expanded, environment "
            "variables are not (a '$' is refused); symbolic links and '..' are resolved, and every run folder "
            "is made inside the resolved directory.",
            locked=True,
        ),
        ParameterSpec(
            "record.max_runs",
            _I,
            100,
            "Most run folders kept in record.directory: as a run starts, the oldest complete runs beyond it are "
            "deleted (logged), never the run being recorded; only folders named by a run id that hold a "
            "metadata.yaml are counted or deleted. 0: no limit.",
            limits=(0, 1_000_000),
            locked=True,
        ),
        ParameterSpec(
            "record.max_bytes",
            _I,
            2**30,
            "Most bytes kept in the complete run folders of record.directory: as a run starts, the oldest are "
            "deleted (logged) until the rest fit (the run being recorded is not counted). 0: no limit.",
            "bytes",
            (0, 2**62),
            locked=True,
        ),
        ParameterSpec(
            "markers.link_faces",
            _I,
            400,
            "Triangles per link mesh that ~/world_markers draws of a spatial arm (namespace robot_links: its "
            "collision geometry, in each link's frame): each mesh simplified to at most this many; 0: every "
            "triangle, the exact collision geometry validity is decided on. Read only: taken when the node starts.",
            "",
            (0, 1_000_000),
            read_only=True,
        ),
        *PLAYBACK_PARAMETERS.values(),
        *STATE_PARAMETERS,
    ],
)

# A parameter is locked exactly when it lies under one of LOCKED_PREFIXES, whichever table specifies it.
assert all(
    spec.locked == spec.name.startswith(LOCKED_PREFIXES)
    for table in (
        WORLD_PARAMETERS,
        PLANNER_PARAMETERS,
        NODE_PARAMETERS,
        SPATIAL_WORLD_PARAMETERS,
        SPATIAL_OBSTACLE_PARAMETERS,
    )
    for spec in (*table.values(), OBSTACLE_PARAMETER, KIND_PARAMETER)
)
