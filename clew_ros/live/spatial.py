"""Spatial worlds (interface.md section 1b) as Foxglove's well-known messages, for the live view.

What the node's ``~/world_markers``, ``~/scene``, ``~/landmarks`` and ``/tf`` show of a spatial run
(:mod:`clew_ros.ros.spatial`), without rclpy, in the frame :data:`~clew_ros.live.messages.FRAME` (metres,
3-D, the palette's colours):

- :func:`world_update`: entities ``bounds`` (lines), ``obstacles`` and ``supports`` (cubes, cylinders,
  spheres at their poses), ``start`` and ``goal`` (the object at its initial and goal placements);
- :func:`links_update`: one entity per link with geometry, ``link/<name>``, in the link's own frame and
  ``frame_locked`` (the arm follows :func:`transforms` as RViz's links follow ``/tf``): primitives as they
  are, meshes as triangle lists simplified to ``max_link_faces`` triangles;
- :func:`transforms`: ``world`` -> every such link at a configuration, and ``world`` -> ``object``;
- :func:`state_update`: entities ``gripper`` (a sphere at the tool centre point: red holding, green open)
  and ``object`` (orange held, blue at rest), as ``~/scene``;
- :func:`landmarks_update`: entity ``landmarks``: the tcp at each landmark, the tree's edges, the
  object's centre at each landmark.

Needs ``foxglove-sdk`` (the ``live`` extra); the live view imports this module only when it draws a
spatial world.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from foxglove.messages import (
    Color,
    CubePrimitive,
    CylinderPrimitive,
    FrameTransform,
    FrameTransforms,
    LinePrimitive,
    LinePrimitiveLineType,
    Point3,
    Pose,
    Quaternion,
    SceneEntity,
    SceneUpdate,
    SpherePrimitive,
    TriangleListPrimitive,
    Vector3,
)
from numpy.typing import NDArray

from clew_ros.live.messages import FRAME, timestamp
from clew_ros.scene.palette import colour
from clew_ros.spatial.transforms import matrix_quaternion, pose_matrix
from clew_ros.spatial.world import SpatialWorld

__all__ = [
    "OBJECT_FRAME",
    "LiveSpatialStyle",
    "landmarks_update",
    "links_update",
    "state_update",
    "transforms",
    "world_update",
]

#: The object's frame in :func:`transforms` (as the node's ``/tf``).
OBJECT_FRAME = "object"

Matrix = NDArray[np.float64]
#: Simplifies a mesh ``(vertices, faces, max_faces) -> (vertices, faces)``.
Simplify = Callable[[np.ndarray, np.ndarray, int], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class LiveSpatialStyle:
    """Sizes of the spatial live view's drawing."""

    max_link_faces: int = 400  # triangles per link mesh: as ~/world_markers draws a recording's links
    line_m: float = 0.005  # lines (bounds, the landmark tree's edges), m: as the RViz markers
    point_m: float = 0.02  # a landmark's tcp, the object's centre, the tcp, m: as the RViz markers
    goal_alpha: float = 0.5  # the object's goal placement, see-through over what is behind it


def _color(key: str, alpha: float = 1.0) -> Color:
    r, g, b, a = colour(key, dark_background=True).fractions(alpha)
    return Color(r=r, g=g, b=b, a=a)


def _parts(matrix: Matrix) -> tuple[Vector3, Quaternion]:
    x, y, z, w = matrix_quaternion(matrix[:3, :3])
    t = matrix[:3, 3]
    return Vector3(x=float(t[0]), y=float(t[1]), z=float(t[2])), Quaternion(x=x, y=y, z=z, w=w)


def _pose(matrix: Matrix) -> Pose:
    position, orientation = _parts(matrix)
    return Pose(position=position, orientation=orientation)


def _point(p: Sequence[float] | np.ndarray) -> Point3:
    return Point3(x=float(p[0]), y=float(p[1]), z=float(p[2]))


def _solid(shape: str, size: Sequence[float], matrix: Matrix, color: Color) -> tuple[str, Any]:
    """A SolidPrimitive (box ``[x, y, z]``, cylinder ``[height, radius]``, sphere ``[radius]``) as
    ``("cubes" | "cylinders" | "spheres", primitive)``."""
    pose = _pose(matrix)
    if shape == "box":
        return "cubes", CubePrimitive(pose=pose, size=Vector3(x=size[0], y=size[1], z=size[2]), color=color)
    if shape == "cylinder":
        diameter = 2 * float(size[1])
        cylinder = CylinderPrimitive(
            pose=pose, size=Vector3(x=diameter, y=diameter, z=size[0]), bottom_scale=1.0, top_scale=1.0, color=color
        )
        return "cylinders", cylinder
    diameter = 2 * float(size[0])
    return "spheres", SpherePrimitive(pose=pose, size=Vector3(x=diameter, y=diameter, z=diameter), color=color)


def _entity(entity_id: str, time_ns: int, solids: Iterable[tuple[str, Any]] = (), **more: Any) -> SceneEntity:
    groups: dict[str, list[Any]] = {}
    for kind, primitive in solids:
        groups.setdefault(kind, []).append(primitive)
    fields = {"frame_id": FRAME, **more}
    for kind, primitives in groups.items():
        fields[kind] = [*fields.get(kind, []), *primitives]
    return SceneEntity(timestamp=timestamp(time_ns), id=entity_id, **fields)


def _bounds_lines(bounds: np.ndarray) -> list[tuple[float, float, float]]:
    x0, y0, z0, x1, y1, z1 = (float(v) for v in bounds)
    corners = [(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]
    lines = []
    for i, a in enumerate(corners):
        for b in corners[i + 1 :]:
            if sum(u != v for u, v in zip(a, b, strict=True)) == 1:
                lines.extend([a, b])
    return lines


def _lines(points: Iterable[Sequence[float] | np.ndarray], key: str, width: float) -> LinePrimitive:
    return LinePrimitive(
        type=LinePrimitiveLineType.LineList, thickness=width, points=[_point(p) for p in points], color=_color(key)
    )


def world_update(world: SpatialWorld, time_ns: int, style: LiveSpatialStyle | None = None) -> SceneUpdate:
    """The world: entities ``bounds``, ``obstacles``, ``supports``, and ``start`` / ``goal`` with an object."""
    style = style or LiveSpatialStyle()
    supports = {s.name for s in world.supports}
    entities = []
    if world.bounds is not None:
        bounds = _lines(_bounds_lines(world.bounds), "field_edge", style.line_m)
        entities.append(_entity("bounds", time_ns, lines=[bounds]))
    for name, key, mine in (("obstacles", "obstacle", False), ("supports", "obstacle_edge", True)):
        solids = [
            _solid(o.shape, o.size, o.pose, _color(key, 0.9)) for o in world.obstacles if (o.name in supports) == mine
        ]
        entities.append(_entity(name, time_ns, solids))
    if world.object is not None:
        thing = world.object
        for name, pose, key, alpha in (
            ("start", thing.initial, "start", 1.0),
            ("goal", thing.goal, "goal", style.goal_alpha),
        ):
            solid = _solid(thing.shape.shape, thing.shape.size, pose_matrix(pose), _color(key, alpha))
            entities.append(_entity(name, time_ns, [solid]))
    return SceneUpdate(entities=entities)


def links_update(
    world: SpatialWorld, time_ns: int, simplify: Simplify | None = None, style: LiveSpatialStyle | None = None
) -> SceneUpdate:
    """The arm's links: entity ``link/<name>`` in frame ``<name>``, ``frame_locked``, in ``arm`` (the gripper
    links ``open``); a mesh as a triangle list simplified by ``simplify`` (left out without it)."""
    style = style or LiveSpatialStyle()
    robot = world.robot
    entities = []
    for link in robot.links:
        color = _color("open" if link.name in robot.gripper_links else "arm")
        solids: list[tuple[str, Any]] = []
        for geometry in link.geometries:
            if geometry.kind in ("box", "cylinder", "sphere"):
                solids.append(_solid(geometry.kind, geometry.size, geometry.origin, color))
            elif simplify is not None and len(geometry.faces):
                vertices, faces = simplify(
                    np.asarray(geometry.vertices), np.asarray(geometry.faces), style.max_link_faces
                )
                corners = np.asarray(vertices)[np.asarray(faces).reshape(-1)]
                triangles = TriangleListPrimitive(
                    pose=_pose(geometry.origin), points=[_point(p) for p in corners], color=color
                )
                solids.append(("triangles", triangles))
        if solids:
            entities.append(_entity(f"link/{link.name}", time_ns, solids, frame_id=link.name, frame_locked=True))
    return SceneUpdate(entities=entities)


def transforms(
    world: SpatialWorld, joints: np.ndarray, object_pose: np.ndarray | None, time_ns: int
) -> FrameTransforms:
    """``world`` -> every link with geometry at ``joints``, and ``world`` -> ``object`` at ``object_pose``
    (6 numbers)."""
    stamp = timestamp(time_ns)
    poses = world.robot.link_poses(np.asarray(joints, dtype=float).tolist())
    if object_pose is not None and world.object is not None:
        poses[OBJECT_FRAME] = pose_matrix(np.asarray(object_pose, dtype=float).tolist())
    out = []
    for child, matrix in poses.items():
        translation, rotation = _parts(matrix)
        out.append(
            FrameTransform(
                timestamp=stamp, parent_frame_id=FRAME, child_frame_id=child, translation=translation, rotation=rotation
            )
        )
    return FrameTransforms(transforms=out)


def state_update(
    world: SpatialWorld,
    joints: np.ndarray,
    gripper: float,
    object_pose: np.ndarray | None,
    time_ns: int,
    *,
    style: LiveSpatialStyle | None = None,
) -> SceneUpdate:
    """Entities ``gripper`` (the tcp: ``closed`` holding, ``open`` not) and ``object`` (``object_held`` /
    ``object_rest``) at one state."""
    style = style or LiveSpatialStyle()
    holding = gripper >= 0.5
    tcp = world.robot.tcp_pose(np.asarray(joints, dtype=float).tolist())
    entities = [
        _entity("gripper", time_ns, [_solid("sphere", (style.point_m,), tcp, _color("closed" if holding else "open"))])
    ]
    if world.object is not None and object_pose is not None:
        thing = world.object.shape
        key = "object_held" if holding else "object_rest"
        matrix = pose_matrix(np.asarray(object_pose, dtype=float).tolist())
        entities.append(_entity("object", time_ns, [_solid(thing.shape, thing.size, matrix, _color(key))]))
    return SceneUpdate(entities=entities)


def landmarks_update(
    world: SpatialWorld, landmarks: Iterable[Any], time_ns: int, style: LiveSpatialStyle | None = None
) -> SceneUpdate:
    """Entity ``landmarks``: a dot at the tcp of each landmark, each landmark's edge to its parent, and a dot
    at the object's centre at each (landmarks: a tree or a plan's, each with ``id``, ``parent``, ``joints``,
    ``object_pose``)."""
    style = style or LiveSpatialStyle()
    robot = world.robot
    items = list(landmarks)
    tcps = {lm.id: robot.tcp_pose(np.asarray(lm.joints, dtype=float).tolist())[:3, 3] for lm in items}
    edges: list[np.ndarray] = []
    for lm in items:
        if lm.parent is not None and lm.parent in tcps:
            edges.extend([tcps[lm.parent], tcps[lm.id]])
    size = Vector3(x=style.point_m, y=style.point_m, z=style.point_m)
    spheres = [
        SpherePrimitive(pose=Pose(position=Vector3(x=float(p[0]), y=float(p[1]), z=float(p[2]))), size=size, color=c)
        for p, c in [(p, _color("tree_node")) for p in tcps.values()]
    ]
    if world.object is not None:
        half = Vector3(x=style.point_m / 2, y=style.point_m / 2, z=style.point_m / 2)
        for lm in items:
            if lm.object_pose is not None and len(lm.object_pose) >= 3:
                centre = np.asarray(lm.object_pose, dtype=float)[:3]
                spheres.append(
                    SpherePrimitive(
                        pose=Pose(position=Vector3(x=float(centre[0]), y=float(centre[1]), z=float(centre[2]))),
                        size=half,
                        color=_color("object_rest"),
                    )
                )
    lines = [_lines(edges, "tree_edge", style.line_m)]
    return SceneUpdate(entities=[_entity("landmarks", time_ns, spheres=spheres, lines=lines)])
