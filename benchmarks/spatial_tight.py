"""Tight motion problems: goals that are grasp poses millimetres from an object and a wall.

MotionBenchMaker's problems put a gripper's fingers a few millimetres from the can or the cube it is about to
grasp, inside bins, cages and shelves. :func:`tighten` turns a problem of :mod:`benchmarks.spatial_scenes` into
one such: at the goal it adds

- an *object*: a box in the tcp's frame (its centre on the approach axis, ``object_offset_m`` along it), grown
  until the robot's exact geometry (coal distance, every link) is ``gap_m`` from it, ``gap_m`` drawn from
  ``gaps_m`` (1-10 mm): between the fingers of a hand, in front of a flange;
- a *wall*: a board whose face is parallel to the approach (its normal along the tcp's x or y, either sign),
  moved in until the robot is another drawn gap from it: the side of a bin or a cell.

Both are collision objects of the scene (ids ``object`` and ``wall``), so the query stays motion-only. A draw
is kept when the start and the goal are valid on the exact reference (:class:`clew_ros.spatial.exact.ExactChecker`:
pinocchio's kinematics and coal, not the planner's checker) and the goal's *witness* holds there: the tcp
backed out straight along its approach axis (``witness_m`` in ``witness_step_m`` steps, inverse kinematics
seeded at the step before) is valid at every 0.002 rad. So every tight problem is solvable, and
its goal is one the sphere model alone refuses (it reaches centimetres past the links).
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from benchmarks.spatial_checker import CONFIG
from benchmarks.spatial_scenes import MotionProblem, _pose_message, robot_and_spheres
from clew_ros.spatial.exact import ExactChecker
from clew_ros.spatial.inverse import IKSettings, InverseKinematics
from clew_ros.spatial.tier import coal_module, robot_distance
from clew_ros.spatial.validate import validation_samples
from clew_ros.spatial.world import spatial_world_from_parameters

__all__ = ["TightSettings", "tighten", "witness"]

Matrix = NDArray[np.float64]


@dataclass(frozen=True)
class TightSettings:
    """How tight problems are drawn (m)."""

    #: The gaps between the robot and the object, and the robot and the wall.
    gaps_m: tuple[float, float] = (0.001, 0.01)
    #: The object's proportions (x, y, z in the tcp's frame) before it is grown to its gap, and where its
    #: centre lies on the approach axis (drawn).
    object_shape: tuple[float, float, float] = (0.5, 1.0, 0.75)
    object_offset_m: tuple[float, float] = (-0.03, 0.04)
    #: The wall's thickness and its two other sides.
    wall_m: tuple[float, float, float] = (0.02, 0.3, 0.3)
    #: The witness: the tcp backed out along its approach this far, in these steps.
    witness_m: float = 0.12
    witness_step_m: float = 0.01
    #: Draws per problem before it is given up.
    tries: int = 24
    #: The bisection stops when the gap is met within this.
    tolerance_m: float = 2e-4


def _grown(distance: Callable[[float], float], low: float, high: float, gap: float, tolerance: float) -> float | None:
    """The parameter in ``[low, high]`` where ``distance(t)`` (falling with t) meets ``gap``, by bisection;
    ``None`` when it is below ``gap`` already at ``low`` or above it at ``high``."""
    if distance(low) < gap or distance(high) > gap:
        return None
    for _ in range(40):
        middle = (low + high) / 2
        d = distance(middle)
        if abs(d - gap) <= tolerance and d >= gap:
            return middle
        low, high = (middle, high) if d > gap else (low, middle)
    return low


def witness(reference: ExactChecker, goal: Matrix, settings: TightSettings) -> bool:
    """Whether the tcp backed out straight along its approach axis from ``goal`` is valid all the way on the
    exact reference (pinocchio + coal, independent of the planner's checker)."""
    robot = reference.world.robot
    solver = InverseKinematics(robot, IKSettings(seeds=0))
    q = goal
    pose = robot.tcp_pose(goal.tolist())
    steps = np.where(robot.prismatic, 0.001, 0.002)
    for k in range(1, math.ceil(settings.witness_m / settings.witness_step_m) + 1):
        target = pose.copy()
        target[:3, 3] -= k * settings.witness_step_m * pose[:3, 2]
        found = solver.solve(target, np.random.default_rng(k), seeds=q[None])
        if not len(found):
            return False
        nxt = found[np.argmin(np.abs(found - q).sum(axis=1))]
        if any(reference.configuration_problem(row) for row in validation_samples(q, nxt, steps)):
            return False
        q = nxt
    return True


def _box_message(size: tuple[float, ...], pose: Matrix) -> dict[str, Any]:
    return {
        "header": {"frame_id": "world"},
        "primitives": [{"type": 1, "dimensions": [round(float(v), 6) for v in size]}],
        "primitive_poses": [_pose_message(pose)],
        "operation": 0,
    }


def tighten(problem: MotionProblem, settings: TightSettings | None = None) -> MotionProblem | None:
    """``problem`` with an object and a wall millimetres from its goal (module docstring); ``None`` when no
    draw of ``settings.tries`` keeps the start valid and the goal's witness."""
    settings = settings or TightSettings()
    coal = coal_module()
    robot, spheres = robot_and_spheres(problem.robot)
    rng = np.random.default_rng([problem.seed, zlib.crc32(problem.name.encode()), 7])
    goal = problem.goal.tolist()
    tcp = robot.tcp_pose(goal)
    shape = np.asarray(settings.object_shape)
    for _ in range(settings.tries):
        gap_object, gap_wall = rng.uniform(*settings.gaps_m, size=2)
        centre = tcp.copy()
        centre[:3, 3] += rng.uniform(*settings.object_offset_m) * tcp[:3, 2]

        def object_gap(scale: float, centre: Matrix = centre) -> float:
            return robot_distance(robot, goal, coal.Box(*(scale * shape)), centre)

        scale = _grown(object_gap, 0.005, 0.3, gap_object, settings.tolerance_m)
        if scale is None:
            continue
        axis = int(rng.integers(0, 2))
        sign = float(rng.choice([-1.0, 1.0]))
        normal = sign * tcp[:3, axis]
        wall_size = [settings.wall_m[1], settings.wall_m[2], settings.wall_m[2]]
        wall_size[axis] = settings.wall_m[0]
        wall_pose = tcp.copy()

        def wall_gap(
            offset: float,
            wall_pose: Matrix = wall_pose,
            normal: NDArray[np.float64] = normal,
            size: list[float] = wall_size,
        ) -> float:
            moved = wall_pose.copy()
            moved[:3, 3] = tcp[:3, 3] + (0.4 - offset) * normal
            return robot_distance(robot, goal, coal.Box(*size), moved)

        offset = _grown(wall_gap, 0.0, 0.4, gap_wall, settings.tolerance_m)
        if offset is None:
            continue
        wall_pose[:3, 3] = tcp[:3, 3] + (0.4 - offset) * normal
        scene = problem.scene
        objects = [dict(o) for o in scene["world"]["collision_objects"]]
        object_size = tuple(float(v) for v in scale * shape)
        objects.append({"id": "object", **_box_message(object_size, centre)})
        objects.append({"id": "wall", **_box_message(tuple(wall_size), wall_pose)})
        tight_scene = {**scene, "world": {"collision_objects": objects}}
        tight = dataclasses.replace(problem, name=f"tight_{problem.name}", scene=tight_scene)
        world = spatial_world_from_parameters(tight.world_parameters(), CONFIG, prepared=(robot, spheres))
        reference = ExactChecker(world)  # pinocchio's kinematics, coal: not the planner's checker
        if reference.configuration_problem(problem.start.tolist()) or reference.configuration_problem(
            problem.goal.tolist()
        ):
            continue
        if not witness(reference, problem.goal, settings):
            continue
        return tight
    return None
