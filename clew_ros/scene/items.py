"""What a scene holds, in world metres: the world, the arm at a configuration, the landmark tree.

Each builder takes core values and returns the geometry every view draws
(the picture, the RViz markers, the Foxglove entities): polygons ``(V, 2)``,
points ``(K, 2)``, segments ``(E, 2, 2)``, all in the plane of the world
frame. Colours are the keys of :data:`clew_ros.scene.palette.PALETTE` named
here (``key`` properties), so that every view colours an item alike.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from clew_ros.planar.kinematics import joint_positions, transform_points
from clew_ros.planar.world import World

__all__ = [
    "HOLDING_THRESHOLD",
    "ArmItems",
    "LandmarkLike",
    "ObstacleItem",
    "TreeItems",
    "WorldItems",
    "arm_items",
    "arm_points",
    "gripper_key",
    "object_key",
    "object_outline",
    "tree_items",
    "world_items",
]

#: A ``gripper`` value (0.0 open, 1.0 holding, as ``~/joint_states`` carries it) at or above which the arm holds.
HOLDING_THRESHOLD = 0.5


class LandmarkLike(Protocol):
    """What is drawn of a landmark: a :class:`~clew_ros.core.tree.Landmark` or a plan's
    :class:`~clew_ros.core.plan.PlanLandmark`."""

    @property
    def id(self) -> int: ...
    @property
    def parent(self) -> int | None: ...
    @property
    def object_pose(self) -> np.ndarray: ...


def arm_points(world: World, q: np.ndarray) -> np.ndarray:
    """Base, joints and tip of the arm at ``q`` ``(n,)`` rad: ``(n + 1, 2)``."""
    points: np.ndarray = joint_positions(world.robot, np.asarray(q, dtype=float)[None])[0]
    return points


def object_outline(world: World, pose: np.ndarray) -> np.ndarray:
    """The object's polygon at ``pose`` ``(x, y, theta)``: ``(V, 2)``; poses ``(L, 3)`` give ``(L, V, 2)``."""
    outline: np.ndarray = transform_points(np.asarray(pose, dtype=float), world.object.polygon)
    return outline


@dataclass(frozen=True)
class ObstacleItem:
    """One obstacle: its name and its polygon ``(V, 2)``."""

    name: str
    vertices: np.ndarray
    key: str = "obstacle"
    edge_key: str = "obstacle_edge"


@dataclass(frozen=True)
class WorldItems:
    """What does not move: the bounds, the obstacles, the object at its start and goal, the grasp points."""

    bounds: np.ndarray  # (4, 2) corners, counter-clockwise from (xmin, ymin)
    obstacles: tuple[ObstacleItem, ...]
    start: np.ndarray  # (V, 2) the object at world.object.initial
    goal: np.ndarray  # (V, 2) the object at the goal
    grasps: np.ndarray  # (G, 2) the grasp points of the object at its start

    bounds_key = "field_edge"
    field_key = "field"
    start_key = "start"
    goal_key = "goal"
    grasp_key = "grasp"

    @property
    def span(self) -> float:
        """The workspace's larger side (m): views that size lines by the world take fractions of it."""
        low, high = self.bounds.min(axis=0), self.bounds.max(axis=0)
        return float(max(high - low))


def world_items(world: World, goal: np.ndarray | None = None) -> WorldItems:
    """The world's items; ``goal`` (x, y, theta) defaults to ``world.object.goal``."""
    xmin, ymin, xmax, ymax = (float(v) for v in world.bounds)
    goal_pose = world.object.goal if goal is None else np.asarray(goal, dtype=float)
    return WorldItems(
        bounds=np.array([[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]]),
        obstacles=tuple(ObstacleItem(o.name, np.asarray(o.vertices, dtype=float)) for o in world.obstacles),
        start=object_outline(world, world.object.initial),
        goal=object_outline(world, goal_pose),
        grasps=transform_points(np.asarray(world.object.initial, dtype=float), world.object.grasps),
    )


@dataclass(frozen=True)
class ArmItems:
    """The arm at one configuration and the object where it is then."""

    points: np.ndarray  # (n + 1, 2) base, joints, tip
    link_width: float  # m, the links' width in the world
    holding: bool
    object: np.ndarray  # (V, 2) the object's outline

    arm_key = "arm"
    joint_key = "joint"

    @property
    def gripper_key(self) -> str:
        return gripper_key(self.holding)

    @property
    def object_key(self) -> str:
        return object_key(self.holding)


def gripper_key(holding: bool) -> str:
    """The gripper's colour: ``closed`` while holding, ``open`` otherwise."""
    return "closed" if holding else "open"


def object_key(holding: bool) -> str:
    """The object's colour: ``object_held`` while carried, ``object_rest`` otherwise."""
    return "object_held" if holding else "object_rest"


def arm_items(world: World, joints: np.ndarray, gripper: float | bool, object_pose: np.ndarray) -> ArmItems:
    """The arm at ``joints`` (n,) rad, holding when ``gripper`` >= :data:`HOLDING_THRESHOLD` (``True``: holding),
    the object at ``object_pose`` (x, y, theta)."""
    return ArmItems(
        arm_points(world, joints),
        float(world.robot.link_width),
        float(gripper) >= HOLDING_THRESHOLD,
        object_outline(world, object_pose),
    )


@dataclass(frozen=True)
class TreeItems:
    """The landmark tree as drawn: a node where the object rests at each landmark, an edge parent -> child.

    ``ids``, ``parents`` and ``poses`` are the landmarks' in the order given;
    ``nodes`` (K, 2) their positions (m), ``edges`` (E, 2, 2) parent -> child
    in the order of the children, ``root`` the index of the landmark without
    a parent (``None``: none given).
    """

    ids: tuple[int, ...]
    parents: tuple[int | None, ...]
    poses: np.ndarray  # (K, 3)
    nodes: np.ndarray  # (K, 2)
    edges: np.ndarray  # (E, 2, 2)
    root: int | None = 0

    edge_key = "tree_edge"
    node_key = "tree_node"

    def outlines(self, world: World) -> np.ndarray:
        """The object at each landmark's placement: ``(K, V, 2)``."""
        return object_outline(world, self.poses).reshape(len(self.ids), -1, 2)

    @classmethod
    def from_landmarks(cls, landmarks: Iterable[LandmarkLike]) -> TreeItems | None:
        """The tree of ``landmarks`` (an edge from each one whose parent is among them); ``None`` without any."""
        return tree_items(landmarks)


def tree_items(landmarks: Iterable[LandmarkLike]) -> TreeItems | None:
    """:class:`TreeItems` of ``landmarks``; ``None`` without any."""
    marks = list(landmarks)
    if not marks:
        return None
    poses = np.array([np.asarray(lm.object_pose, dtype=float)[:3] for lm in marks]).reshape(-1, 3)
    nodes = poses[:, :2].copy()
    index = {lm.id: i for i, lm in enumerate(marks)}
    edges = [
        (nodes[index[lm.parent]], nodes[i])
        for i, lm in enumerate(marks)
        if lm.parent is not None and lm.parent in index
    ]
    root = next((i for i, lm in enumerate(marks) if lm.parent is None), None)
    return TreeItems(
        tuple(int(lm.id) for lm in marks),
        tuple(None if lm.parent is None else int(lm.parent) for lm in marks),
        poses,
        nodes,
        np.array(edges, dtype=float).reshape(-1, 2, 2),
        root,
    )
