"""Plans checked on the exact geometry (clew_ros.spatial.exact: pinocchio + coal on the URDF's meshes, the
obstacles and the object), where the ``spatial-ref`` extra is installed."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pinocchio")
pytest.importorskip("coal")

from clew_ros.core.plan import Plan, PlanSegment
from clew_ros.core.settings import PlannerSettings
from clew_ros.planar.world import read_parameter_file
from clew_ros.spatial.exact import ExactChecker, exact_problems, lowest_point
from clew_ros.spatial.inverse import InverseKinematics
from clew_ros.spatial.offline import checked_plan
from clew_ros.spatial.placements import MovableObject
from clew_ros.spatial.plan import validate_plan
from clew_ros.spatial.space import plan
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters

from .conftest import CONFIG


def load(name: str) -> tuple[SpatialWorld, Plan]:
    path: Path = CONFIG / "spatial" / f"{name}.yaml"
    world = spatial_world_from_parameters(read_parameter_file(path), path.parent)
    return world, Plan.read(path.with_name(f"{name}.witness.json"))


def test_a_planned_pick_and_place_is_free_on_the_exact_geometry() -> None:
    world, _ = load("panda_table_to_table")
    result = plan(world, PlannerSettings(seed=0, time_limit=60.0))
    planned = checked_plan(world, result)
    assert planned.success, planned.message
    assert planned.grasp_count >= 1
    assert exact_problems(world, planned) == []


def test_the_object_is_modelled_resting_and_held() -> None:
    """Without the fingers' leave to touch it, the witness's grasp is a collision with the resting object; the
    held object rides on the tcp (pinocchio's) where the plan's replay puts it."""
    world, witness = load("panda_table_to_table")
    fingerless = replace(world, robot=replace(world.robot, gripper_links=()))
    problems = ExactChecker(fingerless).plan_problems(witness)
    assert any("finger" in p and "the object (resting)" in p for p in problems), problems
    checker = ExactChecker(world)
    transfer = witness.segments[1]
    assert transfer.kind == "transfer"
    assert world.object is not None
    start = pose_matrix(world.object.initial)
    held = np.linalg.inv(checker.tcp_pose(transfer.waypoints[0])) @ start
    end = checker.tcp_pose(transfer.waypoints[-1]) @ held
    assert witness.final_object_pose is not None
    assert np.allclose(end[:3, 3], pose_matrix(witness.final_object_pose.tolist())[:3, 3], atol=1e-4)


def _into_an_obstacle(checker: ExactChecker, world: SpatialWorld, near: np.ndarray) -> np.ndarray:
    """A configuration (a fixed draw) whose links touch an obstacle, the object where it starts."""
    assert world.object is not None
    resting = pose_matrix(world.object.initial)
    rng = np.random.default_rng(7)
    for _ in range(2000):
        q = np.clip(near + rng.normal(0.0, 0.8, world.robot.dof), world.robot.lower, world.robot.upper)
        found = checker.path_problems([q], resting=resting)
        if found and "touches obstacle" in found[0] and "link" in found[0]:
            return q
    raise AssertionError("no configuration into an obstacle drawn")


def test_a_configuration_moved_into_an_obstacle_is_caught() -> None:
    world, witness = load("panda_table_to_table")
    checker = ExactChecker(world)
    assert checker.plan_problems(witness) == []
    first = witness.segments[0].waypoints
    bad = _into_an_obstacle(checker, world, first[0])
    moved = np.array([first[0], bad, *first])
    broken = replace(witness, segments=(PlanSegment("transit", None, moved), *witness.segments[1:]))
    problems = checker.plan_problems(broken)
    assert problems
    assert problems[0].startswith("segment 0 (transit): piece 0 (waypoints 0 -> 1)")
    assert "touches obstacle" in problems[0]
    assert all(p.startswith("segment 0") for p in problems)
    assert validate_plan(world, broken)  # the sphere model covers the meshes: it refuses it too


def test_a_held_object_through_its_support_is_caught() -> None:
    """The held object may touch a support only from above: carried on down 2 cm into the goal's table, the
    transfer collides (the object sinks below the table's top, or the fingers holding it meet the table)."""
    world, witness = load("panda_table_to_table")
    checker = ExactChecker(world)
    assert world.object is not None
    table = world.object.goal_on[0]
    support = next(s for s in world.supports if s.name == table)
    transfer = witness.segments[1].waypoints
    held = np.linalg.inv(checker.tcp_pose(transfer[0])) @ pose_matrix(world.object.initial)
    assert checker.path_problems(transfer, held=held) == []
    placed = checker.tcp_pose(transfer[-1]) @ held
    assert checker.object_problem(placed) == ""
    sunk = placed.copy()
    sunk[2, 3] -= 0.02
    assert lowest_point(world.object.shape, sunk) < support.top - world.tolerances["placement_tolerance"]
    assert f"sinks below the top of support {table!r}" in checker.object_problem(sunk)
    lower = InverseKinematics(world.robot).solve(
        sunk @ np.linalg.inv(held), np.random.default_rng(0), seeds=transfer[-1:]
    )
    assert len(lower)
    q = lower[int(np.argmin(np.abs(lower - transfer[-1]).max(axis=1)))]
    problems = checker.path_problems([*transfer, q], held=held)
    assert len(problems) == 1
    assert problems[0].startswith(f"piece {len(transfer) - 1} ")
    assert repr(table) in problems[0]


def test_lowest_point_is_exact() -> None:
    box = MovableObject("box", (0.2, 0.4, 0.6))
    pose = pose_matrix([0.0, 0.0, 1.0, 0.0, 0.0, 0.3])
    assert lowest_point(box, pose) == pytest.approx(0.7)
    tipped = pose_matrix([0.0, 0.0, 1.0, np.pi / 2, 0.0, 0.0])  # the 0.4 m side now vertical
    assert lowest_point(box, tipped) == pytest.approx(0.8)
    can = MovableObject("cylinder", (0.3, 0.05))
    lying = pose_matrix([0.0, 0.0, 1.0, 0.0, np.pi / 2, 0.0])
    assert lowest_point(can, lying) == pytest.approx(0.95)
    assert lowest_point(can, pose) == pytest.approx(0.85)
