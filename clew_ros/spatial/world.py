"""A spatial world read from its parameters (interface.md section 1b): the robot and its sphere model, the
obstacles (parameters and ``world.scene_file``), bounds, supports, the object with its placements and
grasps, the start and goal, and the checker over them.

:func:`spatial_world_from_parameters` checks every value and raises
:class:`~clew_ros.core.errors.WorldError` naming the parameter at fault; whether the start or the goal is
in collision is left to the planner (an outcome, not an invalid world).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from clew_ros.core.errors import WorldError, short_repr
from clew_ros.core.parameters import LIMITS
from clew_ros.spatial.checker import SpatialChecker
from clew_ros.spatial.parameters import checked_value, world_value
from clew_ros.spatial.placements import (
    MovableObject,
    Support,
    check_placement,
    object_from_parameters,
    supports_from_parameters,
)
from clew_ros.spatial.robot import RobotModel, robot_from_parameters
from clew_ros.spatial.scene import Obstacle, bounds_from_parameters, world_obstacles
from clew_ros.spatial.spheres import SphereModel, SphereSettings, sphere_model

__all__ = ["TOLERANCES", "SpatialObject", "SpatialWorld", "spatial_world_from_parameters"]

#: The spatial world's tolerances (section 1b), keys of ``SpatialWorld.tolerances``: their defaults and
#: ranges are :data:`~clew_ros.spatial.parameters.SPATIAL_WORLD_PARAMETERS`'.
TOLERANCES = (
    "placement_tolerance",
    "grasp_tolerance",
    "grasp_angle_tolerance",
    "goal_tolerance",
    "goal_angle_tolerance",
)


@dataclass(frozen=True, eq=False)
class SpatialObject:
    """The movable object: its shape, its ``initial`` and ``goal`` poses (6 numbers each, each a stable
    placement: ``initial_on`` / ``goal_on`` name the support and face), and ``grasps`` (k, 6): tcp poses in
    the object's frame."""

    shape: MovableObject
    initial: tuple[float, ...]
    goal: tuple[float, ...]
    initial_on: tuple[str, str]
    goal_on: tuple[str, str]
    grasps: NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class SpatialWorld:
    """Everything a spatial world holds, checked; ``checker`` tests the robot against the obstacles."""

    name: str
    robot: RobotModel
    spheres: SphereModel
    obstacles: tuple[Obstacle, ...]
    bounds: NDArray[np.float64] | None
    supports: tuple[Support, ...]
    initial: NDArray[np.float64]
    goal: NDArray[np.float64] | None
    object: SpatialObject | None
    tolerances: Mapping[str, float]
    checker: SpatialChecker
    #: A motion-only query's goal as the tcp's pose ``[x, y, z, roll, pitch, yaw]`` in ``world``
    #: (``world.robot.goal_pose``, instead of ``goal``): any configuration that puts the tcp there.
    goal_pose: tuple[float, ...] | None = None


def _joints(value: Any, robot: RobotModel, parameter: str) -> NDArray[np.float64]:
    try:
        out = np.array([float(v) for v in value])
    except (TypeError, ValueError):
        raise WorldError(parameter, f"expected {robot.dof} joint values, got {short_repr(value)}") from None
    if out.shape != (robot.dof,) or not np.all(np.isfinite(out)):
        raise WorldError(parameter, f"expected {robot.dof} finite values ({', '.join(robot.joint_names)})")
    outside = (out < robot.lower) | (out > robot.upper)
    if np.any(outside):
        j = int(np.argmax(outside))
        raise WorldError(
            parameter, f"{robot.joint_names[j]} = {out[j]} is outside its limits [{robot.lower[j]}, {robot.upper[j]}]"
        )
    return out


def _pose(value: Any, parameter: str) -> tuple[float, ...]:
    try:
        out = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        out = ()
    if len(out) != 6 or not all(math.isfinite(v) for v in out):
        raise WorldError(parameter, f"expected a pose [x, y, z, roll, pitch, yaw], got {short_repr(value)}")
    return out


def _outside(shape: MovableObject, point: NDArray[np.float64]) -> float:
    """How far (m) a point in the object's frame lies outside it (0 inside)."""
    if shape.shape == "box":
        return float(np.linalg.norm(np.maximum(np.abs(point) - np.asarray(shape.size) / 2, 0.0)))
    radial = max(math.hypot(point[0], point[1]) - shape.size[1], 0.0)
    return math.hypot(radial, max(abs(point[2]) - shape.size[0] / 2, 0.0))


def _object(
    tree: Mapping[str, Any], supports: Sequence[Support], tolerance: float, grasp_tolerance: float
) -> SpatialObject:
    shape = object_from_parameters(tree)
    part = tree["object"]
    initial = _pose(world_value(part, "world.object.initial"), "world.object.initial")
    goal = _pose(world_value(part, "world.object.goal"), "world.object.goal")
    initial_on = check_placement(shape, initial, supports, tolerance, "world.object.initial")
    goal_on = check_placement(shape, goal, supports, tolerance, "world.object.goal")
    given = world_value(part, "world.object.grasps")
    try:
        flat = np.array([float(v) for v in given])
    except (TypeError, ValueError):
        flat = np.zeros(1)
    if len(flat) == 0 or len(flat) % 6 or not np.all(np.isfinite(flat)):
        raise WorldError(
            "world.object.grasps", "expected a flat list of tcp poses in the object's frame, 6 numbers each"
        )
    grasps = flat.reshape(-1, 6)
    if len(grasps) > LIMITS.max_grasps:
        raise WorldError(
            "world.object.grasps",
            f"expected at most {LIMITS.max_grasps} grasps (Limits.max_grasps), got {len(grasps)}",
        )
    for k, grasp in enumerate(grasps):
        if _outside(shape, grasp[:3]) > grasp_tolerance:
            raise WorldError(
                "world.object.grasps",
                f"grasp {k} {short_repr(grasp.tolist())}: its tcp is {_outside(shape, grasp[:3]):.4f} m off the "
                f"{shape.shape} (expected it inside, or within world.grasp_tolerance {grasp_tolerance} m)",
            )
    return SpatialObject(
        shape=shape,
        initial=initial,
        goal=goal,
        initial_on=(initial_on[0].name, initial_on[1]),
        goal_on=(goal_on[0].name, goal_on[1]),
        grasps=grasps,
    )


def spatial_world_from_parameters(
    parameters: Mapping[str, Any],
    folder: Path,
    settings: SphereSettings | None = None,
    *,
    prepared: tuple[RobotModel, SphereModel] | None = None,
    exact: bool = True,
) -> SpatialWorld:
    """The spatial world of a ``ros__parameters`` tree (its ``world`` key, ``world.kind: spatial``); paths are
    read relative to ``folder`` (the parameter file's). ``settings`` tune the sphere model. ``prepared``: the
    robot of ``world.robot`` and its sphere model, already loaded (a generator building many worlds around one
    arm); ``world.robot`` is then read only for ``initial`` and ``goal``. ``exact`` false: the planner's checkers
    decide on the sphere model alone (conservative: a benchmark's "before"; the contract asks for the exact
    geometry)."""
    tree = parameters.get("world") if isinstance(parameters, Mapping) else None
    if not isinstance(tree, Mapping):
        raise WorldError("world", f"expected a mapping of world parameters, got {short_repr(tree)}")
    if tree.get("kind") != "spatial":
        raise WorldError("world.kind", f"expected spatial, got {short_repr(tree.get('kind', 'planar'))}")
    name = checked_value(tree, "world.name")
    if len(name) > LIMITS.max_name_chars:
        raise WorldError(
            "world.name",
            f"expected a name of at most {LIMITS.max_name_chars} characters (Limits.max_name_chars), got {len(name)}",
        )
    if not isinstance(tree.get("robot"), Mapping):
        raise WorldError("world.robot", "expected the robot's parameters (urdf or description, base_link, tip_link)")
    robot = robot_from_parameters(tree["robot"], folder) if prepared is None else prepared[0]
    obstacles = world_obstacles(tree, folder, {robot.base_link: robot.base})
    bounds = bounds_from_parameters(tree)
    supports = supports_from_parameters(tree, obstacles)
    tolerances = {key: checked_value(tree, f"world.{key}") for key in TOLERANCES}
    initial = _joints(world_value(tree["robot"], "world.robot.initial"), robot, "world.robot.initial")
    goal = _joints(tree["robot"]["goal"], robot, "world.robot.goal") if "goal" in tree["robot"] else None
    goal_pose = _goal_pose(tree["robot"], goal is not None, "object" in tree)
    thing = None
    if "object" in tree:
        thing = _object(tree, supports, tolerances["placement_tolerance"], tolerances["grasp_tolerance"])
    if thing is None and goal is None and goal_pose is None:
        raise WorldError(
            "world.object",
            "expected an object to move, or world.robot.goal (joints) or world.robot.goal_pose (the tcp's pose) "
            "for a motion-only query",
        )
    spheres = sphere_model(robot, settings) if prepared is None else prepared[1]
    return SpatialWorld(
        name=name,
        robot=robot,
        spheres=spheres,
        obstacles=obstacles,
        bounds=bounds,
        supports=supports,
        initial=initial,
        goal=goal,
        object=thing,
        tolerances=tolerances,
        checker=SpatialChecker(robot, spheres, obstacles, bounds, exact=exact),
        goal_pose=goal_pose,
    )


def _goal_pose(robot: Mapping[str, Any], has_goal: bool, has_object: bool) -> tuple[float, ...] | None:
    """``world.robot.goal_pose`` (interface.md "Motion-only queries"), checked; ``None`` when absent."""
    if "goal_pose" not in robot:
        return None
    if has_goal:
        raise WorldError("world.robot.goal_pose", "expected either world.robot.goal or world.robot.goal_pose, not both")
    if has_object:
        raise WorldError(
            "world.robot.goal_pose",
            "a motion-only query's goal: expected no world.object with it (the object's goal is world.object.goal)",
        )
    return _pose(robot["goal_pose"], "world.robot.goal_pose")
