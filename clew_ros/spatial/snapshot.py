"""The world as it is now (interface.md section 3c), without ROS: a run's snapshot as a parameter tree, the
object's perceived pose snapped onto a stable placement, and a point cloud turned into occupied cubes.

A snapshot is the ``world`` parameter tree of the node's parameters with the start configuration, the
object's pose and the obstacles of the moment written into it (:func:`snapshot_tree`): the run plans in the
world read from that tree, and publishes the tree as its ``~/world_yaml``, so ``clew_plan`` on it reads the
same world and plans the same plan with the same seed.

Point clouds become cubes in :mod:`clew_ros.spatial.voxels`.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.spatial.placements import FACE_NORMALS, MovableObject, Support, face_down, project
from clew_ros.spatial.transforms import matrix_pose

__all__ = [
    "POINTS_PREFIX",
    "AddedObstacle",
    "SnapError",
    "WorldState",
    "cube_name",
    "snap_object_pose",
    "snapshot_tree",
    "start_contacts",
]

#: Sensed cubes are obstacles named ``points/<i>``.
POINTS_PREFIX = "points/"

Array = NDArray[np.float64]


def cube_name(index: int) -> str:
    """The obstacle name of the ``index``-th occupied cube."""
    return f"{POINTS_PREFIX}{index}"


@dataclass(frozen=True)
class AddedObstacle:
    """An obstacle added at run time: ``shape`` (box, cylinder, sphere), ``size`` (SolidPrimitive dimensions,
    m) and ``pose`` ``[x, y, z, roll, pitch, yaw]`` in ``world``."""

    name: str
    shape: str
    size: tuple[float, ...]
    pose: tuple[float, ...]


@dataclass(frozen=True)
class WorldState:
    """What a run starts from besides the parameters; ``None`` / empty: the parameters' own.

    ``initial``: the planned joints (chain order); ``fixed``: other movable joints by name; ``object_pose``:
    a stable placement (6 numbers); ``obstacles``: added obstacles; ``cubes``: the centres (k, 3) of the
    occupied cubes of edge ``cube_m``."""

    initial: tuple[float, ...] | None = None
    fixed: Mapping[str, float] = field(default_factory=dict)
    object_pose: tuple[float, ...] | None = None
    obstacles: tuple[AddedObstacle, ...] = ()
    cubes: Array | None = None
    cube_m: float = 0.0


def snapshot_tree(tree: Mapping[str, Any], state: WorldState) -> dict[str, Any]:
    """The parameter tree ``{"world": {...}}`` of ``tree`` with ``state`` written in (a new tree): the start
    configuration, the fixed joints' positions, the object's initial pose, and the added obstacles and
    occupied cubes appended to ``world.obstacle_names`` / ``world.obstacles``."""
    out = copy.deepcopy(dict(tree))
    world = out["world"]
    robot = world["robot"]
    if state.initial is not None:
        robot["initial"] = [float(v) for v in state.initial]
    if state.fixed:
        names = list(robot.get("fixed_joint_names", []))
        values = [float(v) for v in robot.get("fixed_joint_positions", [])]
        for name, value in state.fixed.items():
            if name in names:
                values[names.index(name)] = float(value)
            else:
                names.append(name)
                values.append(float(value))
        robot["fixed_joint_names"], robot["fixed_joint_positions"] = names, values
    if state.object_pose is not None and "object" in world:
        world["object"]["initial"] = [float(v) for v in state.object_pose]
    added = [(o.name, o.shape, list(o.size), list(o.pose)) for o in state.obstacles]
    if state.cubes is not None:
        edge = [state.cube_m] * 3
        added += [
            (cube_name(i), "box", edge, [float(c[0]), float(c[1]), float(c[2]), 0.0, 0.0, 0.0])
            for i, c in enumerate(state.cubes.tolist())
        ]
    if added:
        names = list(world.get("obstacle_names", []))
        table = dict(world.get("obstacles", {}) or {})
        for name, shape, size, pose in added:
            names.append(name)
            table[name] = {"shape": shape, "size": [float(v) for v in size], "pose": [float(v) for v in pose]}
        world["obstacle_names"], world["obstacles"] = names, table
    return out


class SnapError(ValueError):
    """A perceived object pose that no stable placement lies near enough; the message says why."""


def snap_object_pose(
    thing: MovableObject, pose: Array, supports: Sequence[Support], *, snap_m: float, snap_rad: float
) -> tuple[float, ...]:
    """The stable placement nearest ``pose`` (4x4): its face most nearly down turned exactly down (yaw kept),
    resting on the support under its centre whose top is nearest that face (x, y kept), when the face is
    tilted at most ``snap_rad`` and lies at most ``snap_m`` from that top; else :class:`SnapError` naming the
    face, its tilt and its distance to the support."""
    face, _ = face_down(thing, pose[:3, :3])
    axis, sign = FACE_NORMALS[face]
    tilt = math.acos(max(-1.0, min(1.0, -float(pose[2, axis] * sign))))
    snapped = project(thing, pose, supports)
    text = f"face {face} of the {thing.shape} is the most nearly down, tilted {tilt:.4f} rad from level"
    if snapped is None:
        names = ", ".join(s.name for s in supports) or "none"
        raise SnapError(
            f"{text}; its centre ({pose[0, 3]:.4f}, {pose[1, 3]:.4f}) lies over no support (supports: {names})"
        )
    distance = abs(float(snapped[2, 3] - pose[2, 3]))
    under = [s for s in supports if s.contains(pose[None, :2, 3])[0]]
    support = min(under, key=lambda s: abs(s.top + thing.height(face) - float(snapped[2, 3])))
    if tilt > snap_rad or distance > snap_m:
        raise SnapError(
            f"{text} (state.snap_rad {snap_rad}); it lies {distance:.4f} m from support {support.name}'s top face "
            f"(state.snap_m {snap_m})"
        )
    return tuple(float(v) for v in matrix_pose(snapped))


def start_contacts(world: Any) -> str:
    """What the start configuration of a spatial world touches (the object resting at its initial pose), in
    words (:func:`~clew_ros.spatial.validate.explain_invalid`): the obstacles by name, the object, a
    self-collision, a joint limit or the bounds."""
    from clew_ros.spatial.checker import SpatialChecker
    from clew_ros.spatial.scene import make_obstacle
    from clew_ros.spatial.transforms import pose_matrix
    from clew_ros.spatial.validate import explain_invalid

    thing = world.object
    resting = None
    if thing is not None:
        pose = pose_matrix(list(thing.initial))
        resting = make_obstacle("object", thing.shape.shape, thing.shape.size, pose, "world.object")
    q = np.asarray(world.initial, dtype=float)
    near = _near_the_arm(world.obstacles, world.checker.sphere_positions(q.tolist()), world.spheres.radii)
    checker = SpatialChecker(world.robot, world.spheres, near, world.bounds, resting_object=resting)
    return explain_invalid(checker, q)


def _near_the_arm(obstacles: Sequence[Any], spheres: NDArray[np.float64], radii: NDArray[np.float64]) -> list[Any]:
    """The obstacles whose bounding sphere reaches one of the arm's spheres (the others cannot touch it: each
    is tried alone when a start is explained, and a cloud's cubes are thousands)."""
    if not obstacles:
        return []
    centres = np.array([o.pose[:3, 3] for o in obstacles])
    reach = np.array([float(np.linalg.norm(o.size)) if o.shape != "sphere" else o.size[0] for o in obstacles])
    out = np.zeros(len(obstacles), dtype=np.bool_)
    for start in range(0, len(obstacles), 4096):  # a table of at most 4096 x spheres distances at once
        part = slice(start, start + 4096)
        gap = np.linalg.norm(centres[part, None, :] - spheres[None, :, :], axis=2) - radii[None, :]
        out[part] = np.any(gap <= reach[part, None], axis=1)
    return [o for o, keep in zip(obstacles, out, strict=True) if keep]
