"""Spatial worlds (interface.md section 1b) served by the node: their parameters, goals and messages.

The node plans a ``world.kind: spatial`` world with :func:`clew_ros.spatial.space.plan`, as the offline
planner does (same world, same settings, same seed: same plan). This module is what the node needs around
it, in ROS terms:

- :func:`load_spatial`: the world of the ``world.*`` parameters (relative paths are read from the node's
  working directory: a ROS node does not know which parameter file it was given; ``package://`` and
  absolute paths read the same everywhere), and its :class:`SpatialSetup` (the URDF text, every joint of
  it, the URDF as published).
- :func:`robot_description`: the world's URDF with every mesh ``filename`` a viewer can open:
  ``package://`` URIs are kept; a relative or ``file://`` path becomes ``package://clew_ros/...`` when the
  file lies in this package's installed share directory (an ament install, where RViz and Foxglove resolve
  it), else an absolute ``file://`` URI.
- :func:`goal_from_pose_stamped`: a ``~/goal_pose`` with a full orientation as the object's goal
  placement, refused (:class:`~clew_ros.ros.messages.GoalPoseError`) unless it is a stable placement, with
  the reason (the face most nearly down, its tilt, how far off the support's top face).
- the messages: ``~/world_markers`` (obstacles, supports, the object at its start and goal, the bounds, in
  3-D), ``~/landmarks`` (the tcp at each landmark, the tree's edges, the object at each landmark),
  ``~/scene`` (the object and the tcp), ``~/joint_states`` (every movable joint of the URDF, so
  ``robot_state_publisher`` draws every link), ``/tf`` (``world`` -> the URDF's root link -> every link
  through every joint, and ``world`` -> ``object``), ``~/object_pose`` and the goal as ``PoseStamped`` with
  the full orientation.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import yaml
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from sensor_msgs.msg import JointState
from std_msgs.msg import ColorRGBA, Header, String
from visualization_msgs.msg import Marker, MarkerArray

from clew_ros.core.errors import WorldError
from clew_ros.core.settings import PlannerSettings
from clew_ros.motion.spatial import UrdfTree
from clew_ros.ros.messages import FRAME_ID, QUATERNION_TOLERANCE, GoalPoseError, quoted_text, time_msg
from clew_ros.scene.palette import colour
from clew_ros.spatial.snapshot import POINTS_PREFIX
from clew_ros.spatial.transforms import matrix_quaternion

if TYPE_CHECKING:
    from clew_ros.core.plan import PlanLandmark
    from clew_ros.core.tree import Landmark, LandmarkTree
    from clew_ros.spatial.world import SpatialWorld

__all__ = [
    "OBJECT_FRAME",
    "LinkMarkerSettings",
    "SpatialSetup",
    "SpatialTransform",
    "goal_from_pose_stamped",
    "joint_state",
    "landmark_markers",
    "link_markers",
    "load_spatial",
    "pose_stamped",
    "resolved_parameters",
    "robot_description",
    "scene_markers",
    "state_transforms",
    "static_transforms",
    "with_goal",
    "world_markers",
    "world_yaml_message",
]

#: The object's frame on ``/tf``.
OBJECT_FRAME = "object"
#: Scale (m) of lines and points in the 3-D markers.
_LINE_M = 0.005
_POINT_M = 0.02

Matrix = np.ndarray
#: Joint values or a pose: a sequence of numbers or a numpy vector.
Vector = Sequence[float] | np.ndarray


@dataclass(frozen=True)
class LinkMarkerSettings:
    """How ``~/world_markers`` draws the arm's links (so that a recording alone draws the arm, in frames
    that ``/tf`` places): their collision geometry, each mesh simplified to at most ``max_link_faces``
    triangles (11 Panda links x 400 triangles: about 0.3 MB a message, recorded once per run); 0: every
    triangle, the exact collision geometry (the node's ``markers.link_faces``)."""

    max_link_faces: int = 400


@dataclass(frozen=True, eq=False)
class SpatialSetup:
    """What the node keeps of a spatial world besides the world itself: ``tree`` the ``world`` parameter
    tree (nested), ``folder`` the folder relative paths were read from, ``urdf`` the URDF text,
    ``joints`` its every joint (:class:`~clew_ros.motion.spatial.UrdfTree`), ``description`` the URDF as
    ``~/robot_description`` publishes it."""

    tree: Mapping[str, Any]
    folder: Path
    urdf: str
    joints: UrdfTree
    description: str


def load_spatial(tree: Mapping[str, Any], folder: Path) -> tuple[SpatialWorld, SpatialSetup]:
    """The spatial world of a ``world`` parameter tree (``{"world": {...}}``) and its setup; a
    :class:`~clew_ros.core.errors.WorldError` names the parameter at fault."""
    from clew_ros.spatial.packages import package_paths_from_parameters
    from clew_ros.spatial.robot import read_text, resolve_uri
    from clew_ros.spatial.world import spatial_world_from_parameters

    world = spatial_world_from_parameters(tree, folder)
    robot_tree = tree["world"]["robot"]
    if "urdf" in robot_tree:
        packages = package_paths_from_parameters(robot_tree, folder)
        path = resolve_uri(str(robot_tree["urdf"]), folder, "world.robot.urdf", packages)
        text, urdf_folder = read_text(path, "world.robot.urdf"), path.parent
    else:
        text, urdf_folder = str(robot_tree["description"]), folder
    try:
        joints = UrdfTree(text)
    except (ET.ParseError, ValueError) as error:
        raise WorldError("world.robot.urdf", f"cannot read the URDF's joints: {error}") from None
    setup = SpatialSetup(
        tree=copy.deepcopy(dict(tree)),
        folder=folder,
        urdf=text,
        joints=joints,
        description=robot_description(text, urdf_folder),
    )
    return world, setup


#: The spatial world's parameters that name files (interface.md section 1b), by their path in the tree.
FILE_PARAMETERS = (("robot", "urdf"), ("robot", "srdf"), ("scene_file",))


def resolved_parameters(world_file: Path) -> dict[str, Any]:
    """The ``ros__parameters`` of a spatial world file with the files it names (``world.robot.urdf``,
    ``world.robot.srdf``, ``world.scene_file``) made absolute, relative to the file's folder, as
    ``clew_plan`` reads them (``package://`` and ``file://`` URIs are kept): what a launch file hands the
    node, which reads relative paths from its working directory."""
    from clew_ros.planar.world import read_parameter_file

    parameters = read_parameter_file(world_file)
    world = parameters.get("world")
    if isinstance(world, dict):
        absolute_paths(world, Path(world_file).resolve().parent)
    return parameters


def absolute_paths(world: dict[str, Any], folder: Path) -> None:
    """Make the files a ``world`` tree names (:data:`FILE_PARAMETERS`) and the folders of
    ``world.robot.package_paths`` absolute, relative to ``folder`` (``package://`` and ``file://`` URIs
    kept); in place."""
    for keys in FILE_PARAMETERS:
        tree = world
        for key in keys[:-1]:
            tree = tree.get(key) if isinstance(tree, dict) else None  # type: ignore[assignment]
        value = tree.get(keys[-1]) if isinstance(tree, dict) else None
        if isinstance(value, str) and not value.startswith(("package://", "file://")) and value:
            tree[keys[-1]] = str((folder / value).resolve()) if not Path(value).is_absolute() else value
    robot = world.get("robot")
    paths = robot.get("package_paths") if isinstance(robot, dict) else None
    if isinstance(paths, list) and all(isinstance(p, str) and p for p in paths):
        robot["package_paths"] = [p if Path(p).is_absolute() else str((folder / p).resolve()) for p in paths]  # type: ignore[index]


# ----------------------------------------------------------------------------------------- the URDF


def _share_directory() -> Path | None:
    try:
        from ament_index_python.packages import get_package_share_directory

        return Path(get_package_share_directory("clew_ros")).resolve()
    except Exception:  # noqa: BLE001 - not installed by colcon: no package:// URIs
        return None


def robot_description(urdf_text: str, urdf_folder: Path, share: Path | None = None) -> str:
    """The URDF with every mesh ``filename`` a viewer can open (the module docstring); ``share``: this
    package's share directory (default: the ament index's, if installed)."""
    root = ET.fromstring(urdf_text)
    share = _share_directory() if share is None else share
    changed = False
    for mesh in root.iter("mesh"):
        name = mesh.get("filename", "")
        if not name or name.startswith("package://"):
            continue
        path = Path(name[len("file://") :]) if name.startswith("file://") else Path(name)
        path = (path if path.is_absolute() else urdf_folder / path).resolve()
        uri = path.as_uri()
        if share is not None and path.is_relative_to(share):
            uri = f"package://clew_ros/{path.relative_to(share).as_posix()}"
        mesh.set("filename", uri)
        changed = True
    if not changed:
        return urdf_text
    return ET.tostring(root, encoding="unicode")


# ----------------------------------------------------------------------------------------- goals


def _quaternion_matrix(x: float, y: float, z: float, w: float) -> Matrix:
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _unstable_reason(world: SpatialWorld, pose: Matrix) -> str:
    """Why ``pose`` is no stable placement: the face most nearly down, its tilt, how far it lies off the
    top face of the support under the object's centre (or that none is under it)."""
    from clew_ros.spatial.placements import FACE_NORMALS, face_down

    assert world.object is not None
    thing = world.object.shape
    tolerance = world.tolerances["placement_tolerance"]
    rot, center = pose[:3, :3], pose[:3, 3]
    face, _ = face_down(thing, rot)
    axis, sign = FACE_NORMALS[face]
    tilt = math.acos(max(-1.0, min(1.0, -float(rot[2, axis] * sign))))
    points = thing.face_points(face) @ rot.T + center
    spread = thing.size[1] * math.sin(tilt) if thing.shape == "cylinder" else 0.0
    low, high = float(points[:, 2].min()) - spread, float(points[:, 2].max()) + spread
    under = [s for s in world.supports if s.contains(center[None, :2])[0]]
    text = f"face {face} of the {thing.shape} is the most nearly down, tilted {tilt:.4f} rad from level"
    if not under:
        names = ", ".join(s.name for s in world.supports) or "none"
        return f"{text}; its centre ({center[0]:.4f}, {center[1]:.4f}) lies over no support (supports: {names})"
    support = min(under, key=lambda s: abs(low - s.top))
    off = max(abs(low - support.top), abs(high - support.top))
    return (
        f"{text}; it lies {off:.4f} m off support {support.name}'s top face (z = {support.top:.4f} m; "
        f"the face spans z {low:.4f} to {high:.4f} m; world.placement_tolerance {tolerance} m)"
    )


#: A ``~/goal_pose`` whose pose matrix differs from the world's own goal by at most this (m, and rotation
#: matrix entries) is that goal: a pose message's quaternion changes the goal's numbers by round-off only, and
#: the same seed must give clew_plan's plan (interface.md section 3).
SAME_GOAL = 1e-9


def goal_from_pose_stamped(msg: PoseStamped, world: SpatialWorld) -> np.ndarray:
    """The object's goal placement ``[x, y, z, roll, pitch, yaw]`` of a ``~/goal_pose``, checked: frame
    ``world`` (or empty), finite, a unit quaternion (any orientation), a stable placement (else the
    reason); in a motion-only query (no object) the tcp's goal pose, any orientation within the bounds.
    Raises :class:`~clew_ros.ros.messages.GoalPoseError` saying why not."""
    from clew_ros.spatial.placements import resting_on
    from clew_ros.spatial.transforms import matrix_pose, pose_matrix

    frame = msg.header.frame_id
    if frame not in ("", FRAME_ID):
        raise GoalPoseError(f"goal_pose: header.frame_id must be '{FRAME_ID}' (or empty), got '{quoted_text(frame)}'")
    p, q = msg.pose.position, msg.pose.orientation
    values = [p.x, p.y, p.z, q.x, q.y, q.z, q.w]
    if not all(math.isfinite(v) for v in values):
        raise GoalPoseError("goal_pose: position and orientation must be finite numbers")
    norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise GoalPoseError(f"goal_pose: orientation must be a unit quaternion, got norm {norm:.6g}")
    pose = np.eye(4)
    pose[:3, :3] = _quaternion_matrix(q.x / norm, q.y / norm, q.z / norm, q.w / norm)
    pose[:3, 3] = (p.x, p.y, p.z)
    if world.bounds is not None:
        low, high = world.bounds[:3], world.bounds[3:]
        if np.any(pose[:3, 3] < low) or np.any(pose[:3, 3] > high):
            raise GoalPoseError(
                f"goal_pose: position ({p.x:.6g}, {p.y:.6g}, {p.z:.6g}) lies outside world.bounds "
                f"{np.asarray(world.bounds).tolist()}"
            )
    if world.object is None:  # a motion-only query: the tcp's goal pose
        return _tcp_goal(world, pose)
    tolerance = world.tolerances["placement_tolerance"]
    if resting_on(world.object.shape, pose, world.supports, tolerance) is None:
        raise GoalPoseError(f"goal_pose: not a stable placement: {_unstable_reason(world, pose)}")
    own = np.asarray(world.object.goal, dtype=float)
    if np.max(np.abs(pose_matrix(own.tolist()) - pose)) <= SAME_GOAL:
        return own  # the world's own goal, sent as a pose: the plan is clew_plan's (no quaternion round-off)
    return np.array(matrix_pose(pose), dtype=float)


def _tcp_goal(world: SpatialWorld, pose: Matrix) -> np.ndarray:
    """A motion-only query's ``~/goal_pose``: the tcp's goal pose ``[x, y, z, roll, pitch, yaw]`` (the
    world's own ``world.robot.goal_pose`` when it is that one, so the plan is clew_plan's)."""
    from clew_ros.spatial.transforms import matrix_pose, pose_matrix

    if world.goal_pose is not None and np.max(np.abs(pose_matrix(list(world.goal_pose)) - pose)) <= SAME_GOAL:
        return np.asarray(world.goal_pose, dtype=float)
    return np.array(matrix_pose(pose), dtype=float)


def with_goal(world: SpatialWorld, goal: Vector) -> SpatialWorld:
    """``world`` with the object's goal placement ``goal`` (6 numbers, a stable placement); a motion-only
    query's with the tcp's goal pose ``goal`` (``world.robot.goal_pose``) instead of its own goal."""
    from clew_ros.spatial.placements import check_placement

    if world.object is None:
        if world.goal is not None and np.array_equal(np.asarray(goal, dtype=float), world.goal):
            return world  # its own joint goal
        return dataclasses.replace(world, goal=None, goal_pose=tuple(float(v) for v in goal))
    pose = tuple(float(v) for v in goal)
    support, face = check_placement(
        world.object.shape, pose, world.supports, world.tolerances["placement_tolerance"], "goal_pose"
    )
    return dataclasses.replace(world, object=dataclasses.replace(world.object, goal=pose, goal_on=(support.name, face)))


def _pose_msg(pose: Vector) -> Pose:
    from clew_ros.spatial.transforms import pose_matrix

    matrix = np.asarray(pose, dtype=float)
    if matrix.shape != (4, 4):
        matrix = pose_matrix([float(v) for v in matrix])
    x, y, z, w = matrix_quaternion(matrix[:3, :3])
    t = matrix[:3, 3]
    return Pose(position=Point(x=float(t[0]), y=float(t[1]), z=float(t[2])), orientation=Quaternion(x=x, y=y, z=z, w=w))


def pose_stamped(pose: Vector, time_ns: int) -> PoseStamped:
    """A pose ``[x, y, z, roll, pitch, yaw]`` in ``world`` as a ``PoseStamped`` (the goal, the object)."""
    return PoseStamped(header=Header(stamp=time_msg(time_ns), frame_id=FRAME_ID), pose=_pose_msg(pose))


# ----------------------------------------------------------------------------------------- joints and frames


@dataclass(frozen=True)
class SpatialTransform:
    """The pose of frame ``child`` in frame ``parent`` (a ``/tf`` edge): ``translation`` m and ``rotation``
    a unit quaternion ``(x, y, z, w)``."""

    parent: str
    child: str
    translation: tuple[float, float, float]
    rotation: tuple[float, float, float, float]

    @classmethod
    def of(cls, parent: str, child: str, matrix: Matrix) -> SpatialTransform:
        t = matrix[:3, 3]
        return cls(parent, child, (float(t[0]), float(t[1]), float(t[2])), matrix_quaternion(matrix[:3, :3]))


def _values(setup: SpatialSetup, world: SpatialWorld, joints: Vector) -> dict[str, float]:
    robot = world.robot
    return setup.joints.joint_values(robot.joint_names, np.asarray(joints, dtype=float).tolist(), robot.fixed_positions)


def joint_state(
    setup: SpatialSetup, world: SpatialWorld, joints: Vector, time_ns: int, velocities: Vector
) -> JointState:
    """``~/joint_states``: every movable joint of the URDF (planned and fixed), the planned ones with their
    velocities (the others 0)."""
    values = _values(setup, world, joints)
    speed = dict(zip(world.robot.joint_names, velocities, strict=True))
    names = setup.joints.movable_joint_names
    return JointState(
        header=Header(stamp=time_msg(time_ns), frame_id=""),
        name=names,
        position=[float(values[name]) for name in names],
        velocity=[float(speed.get(name, 0.0)) for name in names],
    )


def state_transforms(
    setup: SpatialSetup, world: SpatialWorld, joints: Vector, object_pose: Vector | None
) -> list[SpatialTransform]:
    """``/tf`` at one state: every movable joint's parent -> child link, and ``world`` -> ``object`` (when
    the world has one); the rest is on ``/tf_static`` (:func:`static_transforms`)."""
    from clew_ros.spatial.transforms import pose_matrix

    values = _values(setup, world, joints)
    moving = setup.joints.joint_transforms(values, movable=True)
    out = [SpatialTransform.of(parent, child, m) for parent, child, m in moving]
    if object_pose is not None and world.object is not None:
        out.append(SpatialTransform.of(FRAME_ID, OBJECT_FRAME, pose_matrix([float(v) for v in object_pose])))
    return out


def static_transforms(setup: SpatialSetup, world: SpatialWorld) -> list[SpatialTransform]:
    """``/tf_static``: ``world`` -> the URDF's root link (``base_link`` at ``world.robot.base_pose``) and
    every fixed joint's parent -> child link, as ``robot_state_publisher`` puts them."""
    values = _values(setup, world, world.initial)
    tree = setup.joints
    root = tree.root_pose(world.robot.base_link, world.robot.base, values)
    out = [SpatialTransform.of(FRAME_ID, tree.root, root)]
    out.extend(SpatialTransform.of(parent, child, m) for parent, child, m in tree.joint_transforms(values, False))
    return out


# ----------------------------------------------------------------------------------------- markers


def _header(time_ns: int) -> Header:
    return Header(stamp=time_msg(time_ns), frame_id=FRAME_ID)


def _color(key: str, alpha: float | None = None) -> ColorRGBA:
    r, g, b, a = colour(key, dark_background=True).fractions(alpha)
    return ColorRGBA(r=r, g=g, b=b, a=a)


def _solid(
    ns: int | str, marker_id: int, shape: str, size: Sequence[float], pose: Any, *, time_ns: int, color: ColorRGBA
) -> Marker:
    """A box, cylinder or sphere (``shape_msgs/SolidPrimitive`` dimensions) at ``pose`` (4x4 or 6 numbers)."""
    kind = {"box": Marker.CUBE, "cylinder": Marker.CYLINDER, "sphere": Marker.SPHERE}[shape]
    marker = Marker(header=_header(time_ns), ns=str(ns), id=marker_id, type=kind, action=Marker.ADD, color=color)
    marker.pose = _pose_msg(pose)
    if shape == "box":
        marker.scale.x, marker.scale.y, marker.scale.z = (float(v) for v in size)
    elif shape == "cylinder":
        marker.scale.x = marker.scale.y = 2.0 * float(size[1])
        marker.scale.z = float(size[0])
    else:
        marker.scale.x = marker.scale.y = marker.scale.z = 2.0 * float(size[0])
    return marker


def _points(ns: str, kind: int, points: Iterable[Vector], *, time_ns: int, color: ColorRGBA, scale: float) -> Marker:
    marker = Marker(header=_header(time_ns), ns=ns, id=0, type=kind, action=Marker.ADD, color=color)
    marker.pose.orientation.w = 1.0
    marker.scale.x = marker.scale.y = marker.scale.z = scale
    marker.points = [Point(x=float(p[0]), y=float(p[1]), z=float(p[2])) for p in points]
    return marker


def _bounds_lines(bounds: np.ndarray) -> list[tuple[float, float, float]]:
    x0, y0, z0, x1, y1, z1 = (float(v) for v in bounds)
    corners = [(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]
    lines = []
    for i, a in enumerate(corners):
        for b in corners[i + 1 :]:
            if sum(u != v for u, v in zip(a, b, strict=True)) == 1:
                lines.extend([a, b])
    return lines


#: Simplifies a mesh ``(vertices, faces, max_faces) -> (vertices, faces)``
#: (:func:`clew_ros.render.spatial.meshes.simplify`, which the node passes in).
Simplify = Callable[[np.ndarray, np.ndarray, int], tuple[np.ndarray, np.ndarray]]


def link_markers(
    world: SpatialWorld, time_ns: int, settings: LinkMarkerSettings, simplify: Simplify | None = None
) -> list[Marker]:
    """The arm's links as ``robot_links`` markers (id: one per geometry), each in its link's frame and
    ``frame_locked``: a primitive as CUBE / CYLINDER / SPHERE, a mesh as a TRIANGLE_LIST simplified by
    ``simplify`` (meshes are left out without it), or whole where ``settings.max_link_faces`` is 0."""
    color = _color("arm")
    markers: list[Marker] = []
    for link in world.robot.links:
        for geometry in link.geometries:
            if geometry.kind in ("box", "cylinder", "sphere"):
                marker = _solid(
                    "robot_links", 0, geometry.kind, geometry.size, geometry.origin, time_ns=time_ns, color=color
                )
            elif len(geometry.faces) and (simplify is not None or settings.max_link_faces == 0):
                vertices, faces = np.asarray(geometry.vertices), np.asarray(geometry.faces)
                if settings.max_link_faces > 0 and simplify is not None:
                    vertices, faces = simplify(vertices, faces, settings.max_link_faces)
                placed = vertices @ geometry.origin[:3, :3].T + geometry.origin[:3, 3]
                corners = placed[faces.reshape(-1)]
                marker = _points("robot_links", Marker.TRIANGLE_LIST, corners, time_ns=time_ns, color=color, scale=1.0)
            else:
                continue
            marker.id = len(markers)
            marker.header.frame_id = link.name
            marker.frame_locked = True
            markers.append(marker)
    return markers


def world_markers(
    world: SpatialWorld, time_ns: int, settings: LinkMarkerSettings | None = None, simplify: Simplify | None = None
) -> MarkerArray:
    """``~/world_markers`` in 3-D: DELETEALL, then ``bounds`` (LINE_LIST), ``points`` (a point cloud's occupied
    cubes ``points/<i>``, one CUBE_LIST), ``obstacles`` and ``supports``
    (CUBE / CYLINDER / SPHERE, id = index in the world's obstacles), ``object_start`` and ``object_goal``
    (the object at its initial and goal placements), and the arm's links (:func:`link_markers`)."""
    markers = [Marker(header=_header(time_ns), action=Marker.DELETEALL)]
    if world.bounds is not None:
        markers.append(
            _points(
                "bounds",
                Marker.LINE_LIST,
                _bounds_lines(world.bounds),
                time_ns=time_ns,
                color=_color("field_edge"),
                scale=_LINE_M,
            )
        )
    supports = {s.name for s in world.supports}
    cubes = [o for o in world.obstacles if o.name.startswith(POINTS_PREFIX)]  # a point cloud's: one CUBE_LIST
    if cubes:
        centres, edge = [o.pose[:3, 3] for o in cubes], cubes[0].size[0]
        color = _color("obstacle", 0.9)
        markers.append(_points("points", Marker.CUBE_LIST, centres, time_ns=time_ns, color=color, scale=edge))
    for index, obstacle in enumerate(world.obstacles):
        if obstacle.name.startswith(POINTS_PREFIX):
            continue
        support = obstacle.name in supports
        ns, key = ("supports", "obstacle_edge") if support else ("obstacles", "obstacle")
        markers.append(
            _solid(ns, index, obstacle.shape, obstacle.size, obstacle.pose, time_ns=time_ns, color=_color(key, 0.9))
        )
    if world.object is not None:
        thing = world.object
        markers.append(
            _solid(
                "object_start",
                0,
                thing.shape.shape,
                thing.shape.size,
                thing.initial,
                time_ns=time_ns,
                color=_color("start"),
            )
        )
        markers.append(
            _solid(
                "object_goal",
                0,
                thing.shape.shape,
                thing.shape.size,
                thing.goal,
                time_ns=time_ns,
                color=_color("goal", 0.5),
            )
        )
    markers.extend(link_markers(world, time_ns, settings or LinkMarkerSettings(), simplify))
    return MarkerArray(markers=markers)


def landmark_markers(world: SpatialWorld, tree: LandmarkTree | Sequence[PlanLandmark], time_ns: int) -> MarkerArray:
    """``~/landmarks`` in 3-D (``tree``: the planner's tree or a plan file's landmarks): ``landmarks``
    (SPHERE_LIST, the tcp at each landmark), ``landmark_edges``
    (LINE_LIST, each landmark's tcp to its parent's) and ``landmark_objects`` (POINTS, the object's centre
    at each landmark)."""
    robot = world.robot
    landmarks: list[Landmark | PlanLandmark] = list(tree)
    tcps = {lm.id: robot.tcp_pose(np.asarray(lm.joints, dtype=float).tolist())[:3, 3] for lm in landmarks}
    edges: list[Vector] = []
    for lm in landmarks:
        if lm.parent is not None and lm.parent in tcps:
            edges.extend([tcps[lm.parent], tcps[lm.id]])
    markers = [
        Marker(header=_header(time_ns), action=Marker.DELETEALL),
        _points(
            "landmarks", Marker.SPHERE_LIST, tcps.values(), time_ns=time_ns, color=_color("tree_node"), scale=_POINT_M
        ),
        _points("landmark_edges", Marker.LINE_LIST, edges, time_ns=time_ns, color=_color("tree_edge"), scale=_LINE_M),
    ]
    if world.object is not None:
        centres = [np.asarray(lm.object_pose, dtype=float)[:3] for lm in landmarks]
        markers.append(
            _points(
                "landmark_objects", Marker.POINTS, centres, time_ns=time_ns, color=_color("object_rest"), scale=_POINT_M
            )
        )
    return MarkerArray(markers=markers)


def scene_markers(
    world: SpatialWorld, joints: Vector, gripper: float, object_pose: Vector | None, time_ns: int
) -> MarkerArray:
    """``~/scene`` at one state: ``gripper`` (a SPHERE at the tcp: red while holding, green when open) and
    ``object`` (the object at ``object_pose``: orange while held, blue at rest). The arm itself is drawn
    from ``~/robot_description`` and ``/tf``."""
    holding = gripper >= 0.5
    tcp = world.robot.tcp_pose(np.asarray(joints, dtype=float).tolist())
    grip = _solid(
        "gripper", 0, "sphere", (_POINT_M,), tcp, time_ns=time_ns, color=_color("closed" if holding else "open")
    )
    markers = [grip]
    if world.object is not None and object_pose is not None:
        thing = world.object.shape
        key = "object_held" if holding else "object_rest"
        markers.append(_solid("object", 0, thing.shape, thing.size, object_pose, time_ns=time_ns, color=_color(key)))
    return MarkerArray(markers=markers)


def world_yaml_message(setup: SpatialSetup, world: SpatialWorld, settings: PlannerSettings, node_name: str) -> String:
    """``~/world_yaml``: the ``world.*`` parameters (with the run's goal, and the files they name as
    absolute paths) and ``planner.*`` as a parameter file ``clew_plan`` reads from anywhere."""
    tree = copy.deepcopy(dict(setup.tree["world"]))
    absolute_paths(tree, setup.folder)
    if world.object is not None and "object" in tree:
        tree["object"]["goal"] = [float(v) for v in world.object.goal]
    if world.object is None and world.goal_pose is not None and isinstance(tree.get("robot"), dict):
        tree["robot"] = {k: v for k, v in tree["robot"].items() if k != "goal"}  # the run's tcp goal instead
        tree["robot"]["goal_pose"] = [float(v) for v in world.goal_pose]
    parameters = {"world": tree, "planner": dataclasses.asdict(settings)}
    document = {node_name: {"ros__parameters": parameters}}
    return String(data=yaml.safe_dump(document, sort_keys=False, default_flow_style=None))
