"""The default viewpoint of a spatial world's picture: from the side from which the robot and its goal are seen.

:func:`open_side_view` tries azimuths around the scene (every :attr:`OpenSideSettings.step_deg`, at the
view's elevation) and keeps the one from which the fewest of the places that matter are hidden behind an
obstacle: the robot's base, the tcp at the start, the object at its start and goal (or a motion-only
query's tcp at its goal). A place is hidden from an azimuth when the ray from it towards the camera
crosses an obstacle's bounding box (supports included: a table hides what lies under it, not what stands
on it) before it leaves the scene. Ties go to the azimuth nearest the given view's (the front right of an
arm whose x points forward), so a world with nothing in the way is seen as before. A shelf whose back
faces the default camera is then seen from its open front.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from clew_ros.render.spatial.camera import View3D
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld

__all__ = ["OpenSideSettings", "open_side_view"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class OpenSideSettings:
    """How :func:`open_side_view` searches."""

    #: Azimuths tried (deg apart), all the way round.
    step_deg: float = 15.0
    #: How far (m) a place is lifted off the surface it rests on before its rays are cast (a goal on a shelf
    #: board is not hidden by that board).
    lift_m: float = 0.02


def _places(world: SpatialWorld, lift: float) -> Array:
    """The places (k, 3) that the picture should show."""
    robot = world.robot
    points = [robot.base[:3, 3], robot.tcp_pose(world.initial.tolist())[:3, 3]]
    if world.object is not None:
        points += [np.asarray(world.object.initial[:3]), np.asarray(world.object.goal[:3])]
    elif world.goal is not None:
        points.append(robot.tcp_pose(world.goal.tolist())[:3, 3])
    elif world.goal_pose is not None:
        points.append(pose_matrix(list(world.goal_pose))[:3, 3])
    out: Array = np.array(points, dtype=np.float64) + np.array([0.0, 0.0, lift])
    return out


def _boxes(world: SpatialWorld) -> tuple[Array, Array, Array]:
    """Each obstacle's oriented bounding box: rotations (m, 3, 3), centres (m, 3), half extents (m, 3)."""
    rotations, centres, halves = [], [], []
    for obstacle in world.obstacles:
        size = obstacle.size
        half = {
            "box": np.asarray(size, dtype=np.float64) / 2,
            "cylinder": np.array([size[1], size[1], size[0] / 2]),
            "sphere": np.full(3, size[0]),
        }[obstacle.shape]
        rotations.append(obstacle.pose[:3, :3])
        centres.append(obstacle.pose[:3, 3])
        halves.append(half)
    if not rotations:
        return np.zeros((0, 3, 3)), np.zeros((0, 3)), np.zeros((0, 3))
    return np.array(rotations), np.array(centres), np.array(halves)


def _hidden(places: Array, direction: Array, boxes: tuple[Array, Array, Array]) -> int:
    """How many of ``places`` a ray towards ``direction`` (unit) leaves through an obstacle's box (slab test in
    each box's frame, the ray's origin outside the box)."""
    rotations, centres, halves = boxes
    if not len(centres):
        return 0
    origin = np.einsum("mji,pmj->pmi", rotations, places[:, None, :] - centres[None])  # (p, m, 3) box frame
    ray = np.einsum("mji,j->mi", rotations, direction)[None]  # (1, m, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        near = (-halves[None] - origin) / ray
        far = (halves[None] - origin) / ray
    low, high = np.minimum(near, far), np.maximum(near, far)
    parallel = np.abs(ray) < 1e-12
    inside_slab = np.abs(origin) <= halves[None]
    low = np.where(parallel, np.where(inside_slab, -np.inf, np.inf), low)
    high = np.where(parallel, np.where(inside_slab, np.inf, -np.inf), high)
    enter, leave = low.max(axis=2), high.min(axis=2)
    inside = np.all(np.abs(origin) < halves[None], axis=2)
    crossed = (enter <= leave) & (leave > 0) & ~inside
    return int(np.any(crossed, axis=1).sum())


def open_side_view(world: SpatialWorld, view: View3D, settings: OpenSideSettings | None = None) -> View3D:
    """``view`` turned to the azimuth from which the fewest places that matter are hidden (the module
    docstring); ``view`` itself when it has an ``eye`` or nothing hides anything from its azimuth."""
    settings = settings or OpenSideSettings()
    if view.eye is not None:
        return view
    places = _places(world, settings.lift_m)
    boxes = _boxes(world)
    steps = max(1, round(360.0 / settings.step_deg))
    best: tuple[int, float, float] | None = None
    for k in range(steps):
        azimuth = math.remainder(view.azimuth_deg + k * 360.0 / steps, 360.0)
        hidden = _hidden(places, dataclasses.replace(view, azimuth_deg=azimuth).direction(), boxes)
        turn = abs(math.remainder(azimuth - view.azimuth_deg, 360.0))
        if best is None or (hidden, turn) < best[:2]:
            best = (hidden, turn, azimuth)
    assert best is not None
    return view if best[1] == 0.0 else dataclasses.replace(view, azimuth_deg=best[2])
