"""Core values as Foxglove's well-known messages: the one module of the live view that knows them.

Everything is drawn in the plane ``z = 0`` of the frame :data:`FRAME`
(metres), with the colours of the renderer (:data:`clew_ros.render.shapes.COLORS`).
Needs ``foxglove-sdk`` (the ``live`` extra); :mod:`clew_ros.live.view` imports
this module only when it starts.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Protocol

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

from clew_ros.core.kinematics import joint_positions, transform_points
from clew_ros.core.world import World
from clew_ros.render.shapes import COLORS

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


class LandmarkLike(Protocol):
    """What is drawn of a landmark: a :class:`~clew_ros.core.tree.Landmark` or a plan's
    :class:`~clew_ros.core.plan.PlanLandmark`."""

    @property
    def id(self) -> int: ...
    @property
    def parent(self) -> int | None: ...
    @property
    def object_pose(self) -> np.ndarray: ...


def timestamp(time_ns: int) -> Timestamp:
    """A Foxglove timestamp from nanoseconds since the epoch."""
    return Timestamp(time_ns // 1_000_000_000, time_ns % 1_000_000_000)


def _color(key: str, alpha: float = 1.0) -> Color:
    r, g, b = COLORS[key]
    return Color(r=r / 255, g=g / 255, b=b / 255, a=alpha)


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


def _scale(world: World) -> float:
    """The workspace's larger side (m): sizes of dots and lines are fractions of it."""
    xmin, ymin, xmax, ymax = (float(v) for v in world.bounds)
    return max(xmax - xmin, ymax - ymin)


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
    scale = _scale(world)
    line = 0.004 * scale
    xmin, ymin, xmax, ymax = (float(v) for v in world.bounds)
    bounds = np.array([[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]])
    goal_pose = np.asarray(world.object.goal if goal is None else goal, dtype=float)
    start = transform_points(world.object.initial, world.object.polygon)
    grasps = transform_points(world.object.initial, world.object.grasps)
    entities = [
        _entity("bounds", time_ns, lines=[_loop(bounds, "field_edge", line)]),
        _entity(
            "obstacles",
            time_ns,
            triangles=[_fill(o.vertices, "obstacle") for o in world.obstacles],
            lines=[_loop(o.vertices, "obstacle_edge", line, z=0.001) for o in world.obstacles],
        ),
        _entity(
            "start",
            time_ns,
            lines=[_loop(start, "start", line)],
            spheres=_dots(grasps, "grasp", 0.012 * scale, z=0.002),
        ),
        _entity("goal", time_ns, lines=[_loop(transform_points(goal_pose, world.object.polygon), "goal", line)]),
    ]
    return SceneUpdate(entities=entities)


def landmarks_update(world: World, landmarks: Iterable[LandmarkLike], time_ns: int) -> SceneUpdate:
    """The landmark tree as entity ``landmarks``: a dot where the object rests at each landmark, an edge from
    each landmark's parent, and the object's outline at each landmark's placement."""
    marks = list(landmarks)
    scale = _scale(world)
    index = {lm.id: i for i, lm in enumerate(marks)}
    poses = np.array([np.asarray(lm.object_pose, dtype=float) for lm in marks]).reshape(-1, 3)
    edges = np.array(
        [[poses[index[lm.parent], :2], poses[i, :2]] for i, lm in enumerate(marks) if lm.parent in index]
    ).reshape(-1, 2, 2)
    outlines = transform_points(poses, world.object.polygon)  # (L, V, 2)
    sides = np.stack([outlines, np.roll(outlines, -1, axis=1)], axis=2).reshape(-1, 2, 2)
    lines = [_segments(sides, "tree_edge", 0.002 * scale, alpha=0.35, z=0.003)]
    if len(edges):
        lines.append(_segments(edges, "tree_edge", 0.003 * scale, z=0.004))
    entity = _entity(
        "landmarks", time_ns, lines=lines, spheres=_dots(poses[:, :2], "tree_node", 0.012 * scale, z=0.005)
    )
    return SceneUpdate(entities=[entity])


def arm_update(world: World, joints: np.ndarray, gripper: float, object_pose: np.ndarray, time_ns: int) -> SceneUpdate:
    """The arm at ``joints`` (n,) rad as entity ``arm`` (links, joints, the gripper: green open, red closed)
    and the object at ``object_pose`` (3,) as entity ``object`` (orange while held)."""
    scale = _scale(world)
    chain = joint_positions(world.robot, np.asarray(joints, dtype=float)[None])[0]  # (n + 1, 2)
    width = max(float(world.robot.link_width), 0.006 * scale)
    holding = gripper > 0.5
    links = LinePrimitive(
        type=LinePrimitiveLineType.LineStrip, thickness=width, points=_points(chain, 0.01), color=_color("arm")
    )
    arm = _entity(
        "arm",
        time_ns,
        lines=[links],
        spheres=[
            *_dots(chain[:-1], "joint", 0.6 * width, z=0.011),
            *_dots(chain[-1:], "closed" if holding else "open", 1.4 * width, z=0.012),
        ],
    )
    outline = transform_points(np.asarray(object_pose, dtype=float), world.object.polygon)
    key = "object_held" if holding else "object_rest"
    carried = _entity(
        "object",
        time_ns,
        triangles=[_fill(outline, key, alpha=0.6, z=0.006)],
        lines=[_loop(outline, key, 0.004 * scale, z=0.007)],
    )
    return SceneUpdate(entities=[arm, carried])


def joint_states(joint_names: Sequence[str], joints: np.ndarray, gripper: float, time_ns: int) -> JointStates:
    """The arm's joints (rad) and the gripper (1.0 holding, 0.0 open), as the node's ``~/joint_states``."""
    states = [JointState(name=name, position=float(q)) for name, q in zip(joint_names, joints, strict=True)]
    states.append(JointState(name=GRIPPER_JOINT, position=float(gripper)))
    return JointStates(timestamp=timestamp(time_ns), joints=states)
