"""Core values as Foxglove's well-known messages: the one module of the live view that knows them.

Everything is drawn in the plane ``z = 0`` of the frame :data:`FRAME`
(metres); the geometry and the colours are the scene description's
(:mod:`clew_ros.scene`), as the renderer and the RViz markers draw them.
Needs ``foxglove-sdk`` (the ``live`` extra); :mod:`clew_ros.live.view` imports
this module only when it starts.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
import shapely
from foxglove.messages import (
    Color,
    JointState,
    JointStates,
    LinePrimitive,
    LinePrimitiveLineType,
    Point3,
    Pose,
    SceneEntity,
    SceneUpdate,
    SpherePrimitive,
    Timestamp,
    TriangleListPrimitive,
    Vector3,
)

from clew_ros.planar.world import World
from clew_ros.scene.items import ArmItems, LandmarkLike, TreeItems, arm_items, tree_items, world_items
from clew_ros.scene.palette import colour

__all__ = [
    "FRAME",
    "GRIPPER_JOINT",
    "LandmarkLike",
    "arm_update",
    "joint_states",
    "landmarks_update",
    "timestamp",
    "world_update",
]

#: The frame every entity is drawn in (the node's fixed frame).
FRAME = "world"
#: The joint after the arm's in ``/clew_plan/joint_states``: 1.0 while grasping (as the node's ``~/joint_states``).
GRIPPER_JOINT = "gripper"


def timestamp(time_ns: int) -> Timestamp:
    """A Foxglove timestamp from nanoseconds since the epoch."""
    return Timestamp(time_ns // 1_000_000_000, time_ns % 1_000_000_000)


def _color(key: str, alpha: float = 1.0) -> Color:
    """The palette's colour ``key`` (:data:`clew_ros.scene.palette.PALETTE`) at opacity ``alpha`` (0-1)."""
    r, g, b, a = colour(key, dark_background=True).fractions(alpha)
    return Color(r=r, g=g, b=b, a=a)


def _points(xy: np.ndarray, z: float = 0.0) -> list[Point3]:
    return [Point3(x=float(x), y=float(y), z=z) for x, y in np.asarray(xy, dtype=float).reshape(-1, 2)]


def _loop(xy: np.ndarray, key: str, thickness: float, *, alpha: float = 1.0, z: float = 0.0) -> LinePrimitive:
    return LinePrimitive(
        type=LinePrimitiveLineType.LineLoop,
        thickness=thickness,
        points=_points(xy, z),
        color=_color(key, alpha),
    )


def _segments(pairs: np.ndarray, key: str, thickness: float, *, alpha: float = 1.0, z: float = 0.0) -> LinePrimitive:
    """A line list: ``pairs`` (E, 2, 2), one segment each."""
    return LinePrimitive(
        type=LinePrimitiveLineType.LineList,
        thickness=thickness,
        points=_points(pairs, z),
        color=_color(key, alpha),
    )


def _dots(xy: np.ndarray, key: str, size: float, *, z: float = 0.0) -> list[SpherePrimitive]:
    return [
        SpherePrimitive(
            pose=Pose(position=Vector3(x=float(x), y=float(y), z=z)),
            size=Vector3(x=size, y=size, z=size),
            color=_color(key),
        )
        for x, y in np.asarray(xy, dtype=float).reshape(-1, 2)
    ]


def _fill(polygon: np.ndarray, key: str, *, alpha: float = 1.0, z: float = 0.0) -> TriangleListPrimitive:
    """A polygon (V, 2), convex or not, as triangles (shapely's constrained Delaunay triangulation)."""
    triangles = shapely.constrained_delaunay_triangles(shapely.Polygon(polygon))
    corners = [np.asarray(t.exterior.coords)[:3] for t in shapely.get_parts(triangles)]
    return TriangleListPrimitive(points=_points(np.array(corners), z), color=_color(key, alpha))


def _entity(
    entity_id: str,
    time_ns: int,
    *,
    lines: list[LinePrimitive] | None = None,
    triangles: list[TriangleListPrimitive] | None = None,
    spheres: list[SpherePrimitive] | None = None,
) -> SceneEntity:
    return SceneEntity(
        timestamp=timestamp(time_ns),
        frame_id=FRAME,
        id=entity_id,
        lines=lines,
        triangles=triangles,
        spheres=spheres,
    )


def world_update(world: World, time_ns: int, *, goal: np.ndarray | None = None) -> SceneUpdate:
    """The world: entities ``bounds``, ``obstacles``, ``start`` (the object where it starts, with its grasp
    points) and ``goal`` (the object at ``goal``, default ``world.object.goal``)."""
    items = world_items(world, goal)
    scale = items.span
    line = 0.004 * scale
    entities = [
        _entity("bounds", time_ns, lines=[_loop(items.bounds, items.bounds_key, line)]),
        _entity(
            "obstacles",
            time_ns,
            triangles=[_fill(o.vertices, o.key) for o in items.obstacles],
            lines=[_loop(o.vertices, o.edge_key, line, z=0.001) for o in items.obstacles],
        ),
        _entity(
            "start",
            time_ns,
            lines=[_loop(items.start, items.start_key, line)],
            spheres=_dots(items.grasps, items.grasp_key, 0.012 * scale, z=0.002),
        ),
        _entity("goal", time_ns, lines=[_loop(items.goal, items.goal_key, line)]),
    ]
    return SceneUpdate(entities=entities)


def landmarks_update(world: World, landmarks: Iterable[LandmarkLike], time_ns: int) -> SceneUpdate:
    """The landmark tree as entity ``landmarks``: a dot where the object rests at each landmark, an edge from
    each landmark's parent, and the object's outline at each landmark's placement."""
    scale = world_items(world).span
    items = tree_items(landmarks)
    lines: list[LinePrimitive] = []
    spheres: list[SpherePrimitive] = []
    if items is None:
        lines.append(_segments(np.zeros((0, 2, 2)), TreeItems.edge_key, 0.002 * scale, alpha=0.35, z=0.003))
    else:
        outlines = items.outlines(world)  # (L, V, 2)
        sides = np.stack([outlines, np.roll(outlines, -1, axis=1)], axis=2).reshape(-1, 2, 2)
        lines.append(_segments(sides, items.edge_key, 0.002 * scale, alpha=0.35, z=0.003))
        if len(items.edges):
            lines.append(_segments(items.edges, items.edge_key, 0.003 * scale, z=0.004))
        spheres = _dots(items.nodes, items.node_key, 0.012 * scale, z=0.005)
    return SceneUpdate(entities=[_entity("landmarks", time_ns, lines=lines, spheres=spheres)])


def arm_update(world: World, joints: np.ndarray, gripper: float, object_pose: np.ndarray, time_ns: int) -> SceneUpdate:
    """The arm at ``joints`` (n,) rad as entity ``arm`` (links, joints, the gripper: green open, red closed)
    and the object at ``object_pose`` (3,) as entity ``object`` (orange while held)."""
    scale = world_items(world).span
    items: ArmItems = arm_items(world, joints, gripper, object_pose)
    chain = items.points  # (n + 1, 2)
    width = max(items.link_width, 0.006 * scale)
    links = LinePrimitive(
        type=LinePrimitiveLineType.LineStrip, thickness=width, points=_points(chain, 0.01), color=_color(items.arm_key)
    )
    arm = _entity(
        "arm",
        time_ns,
        lines=[links],
        spheres=[
            *_dots(chain[:-1], items.joint_key, 0.6 * width, z=0.011),
            *_dots(chain[-1:], items.gripper_key, 1.4 * width, z=0.012),
        ],
    )
    carried = _entity(
        "object",
        time_ns,
        triangles=[_fill(items.object, items.object_key, alpha=0.6, z=0.006)],
        lines=[_loop(items.object, items.object_key, 0.004 * scale, z=0.007)],
    )
    return SceneUpdate(entities=[arm, carried])


def joint_states(joint_names: Sequence[str], joints: np.ndarray, gripper: float, time_ns: int) -> JointStates:
    """The arm's joints (rad) and the gripper (1.0 holding, 0.0 open), as the node's ``~/joint_states``."""
    states = [JointState(name=name, position=float(q)) for name, q in zip(joint_names, joints, strict=True)]
    states.append(JointState(name=GRIPPER_JOINT, position=float(gripper)))
    return JointStates(timestamp=timestamp(time_ns), joints=states)
