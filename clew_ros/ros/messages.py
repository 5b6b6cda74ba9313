"""The one place where core values become ROS 2 messages, and back.

Every function here is pure: it takes core values (``World``, ``LandmarkTree``,
plans, :class:`~clew_ros.motion.playback.Track`) and a stamp, and returns
a standard message, or the reverse (a ``~/goal_pose``; a ``~/trajectory``
becomes a plan again with :func:`clew_ros.recording.trajectory_to_plan`).
The node calls these and nothing else to build what it publishes
(interface.md §3), but for ``/tf``: the TF edges of :mod:`~clew_ros.ros.frames`
become a ``tf2_msgs/msg/TFMessage`` in :func:`clew_ros.recording.cdr.tf_message`.

Conventions:

- everything lies in the plane z = 0 of frame :data:`FRAME_ID`;
- an object pose ``(x, y, theta)`` is a ``Pose`` with a rotation of
  ``theta`` about z;
- a run id is a ``uuid.UUID``; in messages it is the 16 bytes of
  ``unique_identifier_msgs/UUID`` or the 32 hex digits of ``uuid.hex``.
"""

from __future__ import annotations

import json
import math
import uuid
from collections.abc import Iterable, Sequence
from dataclasses import asdict
from typing import Any

import numpy as np
import shapely
import yaml
from action_msgs.msg import GoalInfo, GoalStatus, GoalStatusArray
from builtin_interfaces.msg import Duration, Time
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from sensor_msgs.msg import JointState
from std_msgs.msg import ColorRGBA, Header, String
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from unique_identifier_msgs.msg import UUID
from visualization_msgs.msg import Marker, MarkerArray

from clew_ros.core.parameters import LIMITS
from clew_ros.core.plan import PlanLandmark
from clew_ros.core.settings import PlannerSettings
from clew_ros.core.tree import Landmark, LandmarkTree
from clew_ros.motion.playback import Track, TrackState
from clew_ros.planar.kinematics import transform_points
from clew_ros.planar.world import World, world_to_parameters
from clew_ros.ros.urdf import robot_urdf, visual_width_m
from clew_ros.scene.items import TreeItems, WorldItems, arm_items, tree_items, world_items
from clew_ros.scene.palette import colour

__all__ = [
    "FRAME_ID",
    "GoalPoseError",
    "event_message",
    "feedback_status",
    "goal_from_pose_stamped",
    "goal_pose_stamped",
    "goal_status_array",
    "joint_state",
    "joint_trajectory",
    "landmark_markers",
    "object_pose_stamped",
    "playback_messages",
    "pose_msg",
    "quaternion_to_yaw",
    "quoted_text",
    "robot_description_message",
    "scene_markers",
    "time_msg",
    "uuid_msg",
    "world_markers",
    "world_messages",
    "world_yaml_message",
    "yaw_to_quaternion",
]

FRAME_ID = "world"
#: Tolerance on |q| - 1 for a goal orientation quaternion, and on its x, y (a rotation about z only).
QUATERNION_TOLERANCE = 1e-3


class GoalPoseError(ValueError):
    """A ``~/goal_pose`` message the node cannot plan to; ``str()`` says why."""


# --------------------------------------------------------------------------- basics


def time_msg(time_ns: int) -> Time:
    return Time(sec=int(time_ns // 1_000_000_000), nanosec=int(time_ns % 1_000_000_000))


def duration_msg(duration_ns: int) -> Duration:
    return Duration(sec=int(duration_ns // 1_000_000_000), nanosec=int(duration_ns % 1_000_000_000))


def duration_ns(msg: Duration) -> int:
    return int(msg.sec) * 1_000_000_000 + int(msg.nanosec)


def _header(time_ns: int, frame_id: str = FRAME_ID) -> Header:
    return Header(stamp=time_msg(time_ns), frame_id=frame_id)


def yaw_to_quaternion(yaw: float) -> Quaternion:
    return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))


def quaternion_to_yaw(q: Quaternion) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def pose_msg(pose: np.ndarray, z: float = 0.0) -> Pose:
    """A planar pose ``(x, y, theta)`` as a ``Pose``."""
    return Pose(position=Point(x=float(pose[0]), y=float(pose[1]), z=z), orientation=yaw_to_quaternion(float(pose[2])))


def _point(xy: Iterable[float], z: float = 0.0) -> Point:
    x, y = xy
    return Point(x=float(x), y=float(y), z=z)


def _color(key: str, alpha: float | None = None) -> ColorRGBA:
    """The palette's colour ``key`` (:data:`clew_ros.scene.palette.PALETTE`), opacity ``alpha`` (0-1) if given."""
    r, g, b, a = colour(key, dark_background=True).fractions(alpha)
    return ColorRGBA(r=r, g=g, b=b, a=a)


# --------------------------------------------------------------------------- goals


def quoted_text(text: str, limit: int = LIMITS.max_quoted_chars) -> str:
    """``text`` from a peer as a log line or an event may quote it: printable characters only (each other one
    is shown as ``?``), at most ``limit`` of them, then ``...(N characters)`` when it was longer."""
    shown = "".join(c if c.isprintable() else "?" for c in text[:limit])
    return shown if len(text) <= limit else f"{shown}...({len(text)} characters)"


def goal_from_pose_stamped(msg: PoseStamped, world: World) -> np.ndarray:
    """The object goal ``(x, y, yaw)`` of a ``~/goal_pose`` message, checked.

    The frame must be ``world`` (an empty frame id is read as ``world``);
    position and orientation must be finite, the quaternion of unit length
    and a rotation about z only; ``(x, y)`` must lie inside ``world.bounds``.
    ``position.z`` is ignored. Raises :class:`GoalPoseError` saying why not.
    """
    frame = msg.header.frame_id
    if frame not in ("", FRAME_ID):
        raise GoalPoseError(f"goal_pose: header.frame_id must be '{FRAME_ID}' (or empty), got '{quoted_text(frame)}'")
    p, q = msg.pose.position, msg.pose.orientation
    values = [p.x, p.y, p.z, q.x, q.y, q.z, q.w]
    if not all(math.isfinite(v) for v in values):
        raise GoalPoseError(
            f"goal_pose: position and orientation must be finite numbers, got position "
            f"({p.x}, {p.y}, {p.z}) orientation ({q.x}, {q.y}, {q.z}, {q.w})"
        )
    norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise GoalPoseError(f"goal_pose: orientation must be a unit quaternion, got norm {norm:.6g}")
    if abs(q.x) > QUATERNION_TOLERANCE or abs(q.y) > QUATERNION_TOLERANCE:
        raise GoalPoseError(
            f"goal_pose: orientation must be a rotation about z only (x = y = 0), got x={q.x:.6g} y={q.y:.6g}"
        )
    xmin, ymin, xmax, ymax = (float(v) for v in world.bounds)
    if not (xmin <= p.x <= xmax and ymin <= p.y <= ymax):
        raise GoalPoseError(
            f"goal_pose: position ({p.x:.6g}, {p.y:.6g}) lies outside world.bounds [{xmin}, {ymin}, {xmax}, {ymax}]"
        )
    return np.array([p.x, p.y, quaternion_to_yaw(q)], dtype=float)


def goal_pose_stamped(goal: np.ndarray, time_ns: int) -> PoseStamped:
    """An object goal ``(x, y, theta)`` as the ``PoseStamped`` RViz's 2D Goal Pose tool sends."""
    return PoseStamped(header=_header(time_ns), pose=pose_msg(goal))


def object_pose_stamped(pose: np.ndarray, time_ns: int) -> PoseStamped:
    return PoseStamped(header=_header(time_ns), pose=pose_msg(pose))


# --------------------------------------------------------------------------- runs


def uuid_msg(run_id: uuid.UUID) -> UUID:
    return UUID(uuid=list(run_id.bytes))


def goal_status_array(entries: Iterable[tuple[uuid.UUID, int, int]], time_ns: int) -> GoalStatusArray:
    """``~/status`` from ``(run id, accepted time (ns), GoalStatus.STATUS_*)`` entries."""
    msg = GoalStatusArray()
    for run_id, stamp_ns, status in entries:
        info = GoalInfo(goal_id=uuid_msg(run_id), stamp=time_msg(stamp_ns))
        msg.status_list.append(GoalStatus(goal_info=info, status=int(status)))
    return msg


def _json_number(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def feedback_status(
    run_id: uuid.UUID, *, landmarks: int, best_distance: float, elapsed_s: float, phase: str
) -> DiagnosticStatus:
    """``~/feedback``: run id, landmarks, best distance to goal (m; ``inf`` before any), elapsed (s)."""
    return DiagnosticStatus(
        level=DiagnosticStatus.OK,
        name="clew_planner",
        message=phase,
        hardware_id=run_id.hex,
        values=[
            KeyValue(key="run_id", value=run_id.hex),
            KeyValue(key="landmarks", value=str(int(landmarks))),
            KeyValue(key="best_distance", value=f"{best_distance:.6g}"),
            KeyValue(key="elapsed", value=f"{elapsed_s:.3f}"),
            KeyValue(key="phase", value=phase),
        ],
    )


def event_message(run_id: uuid.UUID, event: str, time_s: float, /, **fields: Any) -> String:
    """One ``~/events`` JSON object: ``run_id``, ``event``, ``time`` and ``fields``.

    Non-finite numbers become ``null`` so that the text is strict JSON.
    """
    payload = {"run_id": run_id.hex, "event": event, "time": time_s}
    payload.update(fields)

    def clean(value: Any) -> Any:
        if isinstance(value, (float, np.floating)):
            return _json_number(float(value))
        if isinstance(value, np.integer):
            return int(value)
        if isinstance(value, np.ndarray):
            return [clean(v) for v in value.tolist()]
        if isinstance(value, (list, tuple)):
            return [clean(v) for v in value]
        if isinstance(value, dict):
            return {k: clean(v) for k, v in value.items()}
        return value

    return String(data=json.dumps(clean(payload), allow_nan=False))


def world_yaml_message(world: World, settings: PlannerSettings, node_name: str = "clew_planner") -> String:
    """``~/world_yaml``: the node's ``world.*`` and ``planner.*`` as a parameter file ``clew_plan`` reads."""
    parameters = world_to_parameters(world)
    parameters["planner"] = asdict(settings)
    document = {node_name: {"ros__parameters": parameters}}
    return String(data=yaml.safe_dump(document, sort_keys=False, default_flow_style=None))


def world_messages(
    world: World, settings: PlannerSettings, node_name: str, time_ns: int
) -> list[tuple[str, String | MarkerArray]]:
    """What a run puts out of its problem, ``(topic name, message)`` in order: ``~/world_yaml``,
    ``~/world_markers`` and ``~/robot_description`` (the arm's TF is :mod:`~clew_ros.ros.frames`')."""
    return [
        ("world_yaml", world_yaml_message(world, settings, node_name)),
        ("world_markers", world_markers(world, time_ns)),
        ("robot_description", robot_description_message(world)),
    ]


# --------------------------------------------------------------------------- markers

_LINE_WIDTH_M = 0.01


def _marker(
    ns: str,
    marker_id: int,
    kind: int,
    time_ns: int,
    color: ColorRGBA,
    *,
    scale: float = _LINE_WIDTH_M,
    points: Iterable[Point] = (),
) -> Marker:
    marker = Marker(header=_header(time_ns), ns=ns, id=marker_id, type=kind, action=Marker.ADD, color=color)
    marker.pose.orientation.w = 1.0
    marker.scale.x = marker.scale.y = marker.scale.z = scale
    marker.points = list(points)
    return marker


def _delete_all(time_ns: int) -> Marker:
    return Marker(header=_header(time_ns), action=Marker.DELETEALL)


def _outline(vertices: np.ndarray) -> list[Point]:
    return [_point(v) for v in vertices] + [_point(vertices[0])]


def _triangles(vertices: np.ndarray) -> list[Point]:
    """A simple polygon as TRIANGLE_LIST points (constrained Delaunay, so concave polygons fill right)."""
    triangles = shapely.constrained_delaunay_triangles(shapely.Polygon(vertices))
    points: list[Point] = []
    for triangle in shapely.get_parts(triangles):
        ring = np.asarray(triangle.exterior.coords)[:3]
        points.extend(_point(v) for v in ring)
    return points


def world_markers(world: World, time_ns: int, goal: np.ndarray | None = None) -> MarkerArray:
    """``~/world_markers``: bounds, obstacles, the object at its start and at ``goal``.

    ``goal`` defaults to ``world.object.goal``. Namespaces: ``bounds``,
    ``obstacles`` (filled, id = index in ``world.obstacles``),
    ``obstacle_outlines``, ``object_start``, ``object_goal``, ``grasps``
    (the grasp points at the start placement). DELETEALL comes first.
    Geometry and colours are the scene's (:func:`clew_ros.scene.items.world_items`).
    """
    items = world_items(world, goal)
    markers = [_delete_all(time_ns)]
    markers.append(
        _marker("bounds", 0, Marker.LINE_STRIP, time_ns, _color(items.bounds_key), points=_outline(items.bounds))
    )
    for index, obstacle in enumerate(items.obstacles):
        markers.append(
            _marker(
                "obstacles",
                index,
                Marker.TRIANGLE_LIST,
                time_ns,
                _color(obstacle.key, 0.9),
                scale=1.0,
                points=_triangles(obstacle.vertices),
            )
        )
        markers.append(
            _marker(
                "obstacle_outlines",
                index,
                Marker.LINE_STRIP,
                time_ns,
                _color(obstacle.edge_key),
                points=_outline(obstacle.vertices),
            )
        )
    markers.append(
        _marker(
            "object_start",
            0,
            Marker.LINE_STRIP,
            time_ns,
            _color(items.start_key),
            scale=2 * _LINE_WIDTH_M,
            points=_outline(items.start),
        )
    )
    markers.append(
        _marker(
            "object_goal",
            0,
            Marker.LINE_STRIP,
            time_ns,
            _color(items.goal_key),
            scale=2 * _LINE_WIDTH_M,
            points=_outline(items.goal),
        )
    )
    markers.append(
        _marker(
            "grasps",
            0,
            Marker.SPHERE_LIST,
            time_ns,
            _color(items.grasp_key),
            scale=0.03,
            points=[_point(g) for g in items.grasps],
        )
    )
    return MarkerArray(markers=markers)


def landmark_markers(
    tree: LandmarkTree | Sequence[PlanLandmark], time_ns: int, polygon: np.ndarray | None = None
) -> MarkerArray:
    """``~/landmarks``: DELETEALL, then the tree (or a plan's landmarks) drawn at the object's resting positions.

    Namespaces: ``landmarks`` (one SPHERE_LIST, the root in the start's
    colour, the others in the tree's), ``tree_edges`` (LINE_LIST parent ->
    child), ``landmark_ids`` (TEXT_VIEW_FACING, marker id = landmark id) and,
    given the object's ``polygon`` (its own frame), ``landmark_outlines`` (a
    LINE_STRIP of the object at each landmark's placement, marker id =
    landmark id). Geometry and colours are the scene's
    (:func:`clew_ros.scene.items.tree_items`).
    """
    landmarks: list[Landmark | PlanLandmark] = list(tree)
    items = tree_items(landmarks)
    markers = [_delete_all(time_ns)]
    if items is None:
        markers.append(_marker("landmarks", 0, Marker.SPHERE_LIST, time_ns, _color(TreeItems.node_key), scale=0.04))
        markers.append(_marker("tree_edges", 0, Marker.LINE_LIST, time_ns, _color(TreeItems.edge_key, 0.8)))
        return MarkerArray(markers=markers)

    def key(index: int) -> str:
        return WorldItems.start_key if index == items.root else items.node_key

    spheres = _marker(
        "landmarks", 0, Marker.SPHERE_LIST, time_ns, _color(items.node_key), scale=0.04, points=map(_point, items.nodes)
    )
    spheres.colors = [_color(key(i)) for i in range(len(items.ids))]
    markers.append(spheres)
    edges = [_point(end) for edge in items.edges for end in edge]
    markers.append(_marker("tree_edges", 0, Marker.LINE_LIST, time_ns, _color(items.edge_key, 0.8), points=edges))
    for node, landmark_id in zip(items.nodes, items.ids, strict=True):
        text = _marker("landmark_ids", landmark_id, Marker.TEXT_VIEW_FACING, time_ns, _color("label"), scale=0.06)
        text.pose.position = _point(node, z=0.06)
        text.text = str(landmark_id)
        markers.append(text)
    if polygon is not None:
        outlines = transform_points(items.poses, np.asarray(polygon, dtype=float)).reshape(len(items.ids), -1, 2)
        markers.extend(
            _marker(
                "landmark_outlines",
                landmark_id,
                Marker.LINE_STRIP,
                time_ns,
                _color(key(i), 0.6),
                points=_outline(outline),
            )
            for i, (landmark_id, outline) in enumerate(zip(items.ids, outlines, strict=True))
        )
    return MarkerArray(markers=markers)


# --------------------------------------------------------------------------- the arm


def robot_description_message(world: World) -> String:
    """``~/robot_description``: the URDF of the arm (:func:`clew_ros.ros.urdf.robot_urdf`)."""
    return String(data=robot_urdf(world))


def scene_markers(
    world: World, joints: np.ndarray, gripper: float, object_pose: np.ndarray, time_ns: int
) -> MarkerArray:
    """``~/scene``: the arm at ``joints`` ``(n,)`` rad, its gripper and the object at ``object_pose``.

    Namespaces (one marker each, id 0, replaced at every sample): ``arm``
    (LINE_STRIP base -> joints -> tip, as wide as the links), ``arm_joints``
    (SPHERE_LIST at the base and the joints), ``gripper`` (a SPHERE at the
    tip, green and small while open, red and larger while holding: ``gripper``
    >= 0.5), ``object`` (the object's outline, orange while held, blue at rest).
    Geometry and colours are the scene's (:func:`clew_ros.scene.items.arm_items`), as ``clew_render`` draws them.
    """
    items = arm_items(world, joints, gripper, object_pose)
    points = items.points
    width = visual_width_m(world.robot)
    arm = _marker("arm", 0, Marker.LINE_STRIP, time_ns, _color(items.arm_key), scale=width, points=map(_point, points))
    joints_marker = _marker(
        "arm_joints",
        0,
        Marker.SPHERE_LIST,
        time_ns,
        _color(items.joint_key),
        scale=1.5 * width,
        points=map(_point, points[:-1]),
    )
    grip = _marker(
        "gripper", 0, Marker.SPHERE, time_ns, _color(items.gripper_key), scale=(3.0 if items.holding else 2.0) * width
    )
    grip.pose.position = _point(points[-1])
    outline = _marker(
        "object",
        0,
        Marker.LINE_STRIP,
        time_ns,
        _color(items.object_key),
        scale=2 * _LINE_WIDTH_M,
        points=_outline(items.object),
    )
    return MarkerArray(markers=[arm, joints_marker, grip, outline])


# --------------------------------------------------------------------------- trajectory


def joint_trajectory(track: Track, time_ns: int) -> JointTrajectory:
    """``~/trajectory``: the track's points; ``header.stamp`` is when playback starts.

    Every point carries positions, velocities and accelerations of every
    joint (``gripper``: velocity and acceleration 0; a spatial track has no
    ``gripper`` joint), as ``joint_trajectory_controller`` expects.
    """
    msg = JointTrajectory(header=_header(time_ns), joint_names=list(track.joint_names))
    for k in range(len(track.times_ns)):
        gripper, zero = ([float(track.gripper[k])], [0.0]) if track.gripper_joint else ([], [])
        msg.points.append(
            JointTrajectoryPoint(
                positions=[float(v) for v in track.positions[k]] + gripper,
                velocities=[float(v) for v in track.velocities[k]] + zero,
                accelerations=[float(v) for v in track.accelerations[k]] + zero,
                time_from_start=duration_msg(int(track.times_ns[k])),
            )
        )
    return msg


def playback_messages(
    joint_names: list[str], state: TrackState, time_ns: int
) -> list[tuple[str, JointState | PoseStamped]]:
    """``~/joint_states`` (positions and velocities) and ``~/object_pose`` at one played-back state,
    ``(topic name, message)``; the arm's ``/tf`` and ``~/scene`` go with them."""
    return [
        ("joint_states", joint_state(joint_names, state.joints, state.gripper, time_ns, state.velocities)),
        ("object_pose", object_pose_stamped(state.object_pose, time_ns)),
    ]


def joint_state(
    joint_names: list[str], joints: np.ndarray, gripper: float, time_ns: int, velocities: np.ndarray | None = None
) -> JointState:
    """``~/joint_states``: ``joint_names`` already ends with ``gripper``.

    ``velocities`` (rad/s, one per arm joint) fill ``velocity``, with 0.0 for
    the gripper, so that it has one entry per name; ``None``: no ``velocity``.
    """
    msg = JointState(
        header=_header(time_ns, frame_id=""),
        name=list(joint_names),
        position=[float(v) for v in joints] + [float(gripper)],
    )
    if velocities is not None:
        msg.velocity = [float(v) for v in velocities] + [0.0]
    return msg
