"""The improvement on arms of many joints (issue 46, :mod:`clew_ros.planar.improve.many`): a first plan of the
snake family improved is valid at the validator's 0.002 rad, never longer than the first, the same for the
same seed; its postures solved again along the tip's path shorten it."""

from __future__ import annotations

import dataclasses
from functools import cache

import numpy as np
import pytest

from clew_ros.core.clew import IMPROVE_STREAM, PlanResult
from clew_ros.core.improve import joint_travel, plan_score
from clew_ros.core.plan import Plan
from clew_ros.core.settings import Outcome, PlannerSettings, Termination
from clew_ros.core.space import PlanningContext
from clew_ros.planar.improve import Improvement, _Improver, _pieces, improve
from clew_ros.planar.plan import validate_plan
from clew_ros.planar.space import PlanarSpace, plan
from clew_ros.planar.world import World
from clew_ros.worlds import generate


@cache
def _first_plan(world_seed: int, planner_seed: int) -> tuple[World, PlanResult]:
    """A snake world and the planner's first plan in it (no improvement)."""
    world = generate("snake", world_seed).world()
    result = plan(world, PlannerSettings(seed=planner_seed, time_limit=60.0, improve_time=0.0))
    assert result.outcome is Outcome.SUCCEEDED, result.message
    return world, result


def _improved(world: World, first: PlanResult, planner_seed: int) -> Improvement:
    settings = PlannerSettings(seed=planner_seed, time_limit=120.0)
    ctx = PlanningContext(
        PlanarSpace(world), settings, np.random.default_rng([planner_seed, IMPROVE_STREAM]), Termination(120.0)
    )
    assert first.final_object_pose is not None
    return improve(world, ctx, first.segments, first.final_object_pose, world.object.goal)


@pytest.mark.parametrize(("world_seed", "planner_seed"), [(24, 1), (7, 1), (7, 0)])
def test_a_many_joint_plan_improved_is_valid_never_longer_and_the_same_for_the_same_seed(
    world_seed: int, planner_seed: int
) -> None:
    world, first = _first_plan(world_seed, planner_seed)
    assert world.robot.dof >= 15
    one = _improved(world, first, planner_seed)
    two = _improved(world, first, planner_seed)
    assert not one.refused
    assert one.transfers <= one.first_transfers
    assert one.travel <= one.first_travel + 1e-9
    assert one.travel == pytest.approx(joint_travel(one.segments), abs=1e-9)
    assert len(one.segments) == len(two.segments)
    for a, b in zip(one.segments, two.segments, strict=True):  # same seed, same plan
        assert (a.kind, a.grasp) == (b.kind, b.grasp)
        assert np.array_equal(np.array(a.waypoints), np.array(b.waypoints))
    improved = dataclasses.replace(first, segments=one.segments, final_object_pose=one.final_object_pose)
    assert validate_plan(world, Plan.from_result(world, improved), step_rad=0.002) == []


def test_postures_solved_again_along_the_tip_path_shorten_a_wandering_plan() -> None:
    world, first = _first_plan(24, 1)  # 15 links of equal length, loose limits: EXPLORE's postures wander
    assert first.final_object_pose is not None
    ctx = PlanningContext(
        PlanarSpace(world), PlannerSettings(seed=1), np.random.default_rng([1, IMPROVE_STREAM]), Termination(120.0)
    )
    improver = _Improver(world, ctx, _pieces(world, first.segments), world.object.goal)
    before = plan_score(improver.pieces)
    assert improver.resolve_postures()
    after = plan_score(improver.pieces)
    assert after[0] == before[0]  # the same transfers, the same grasps, the object moved along the same path
    assert after[1] < 0.9 * before[1]  # before any shortcut (76.6 -> 65.9 rad when written)
    for old, new in zip(_pieces(world, first.segments), improver.pieces, strict=True):
        assert (old.kind, old.grasp) == (new.kind, new.grasp)
        # each piece ends holding or leaving the object where it did (the tip at the same pose)
        assert np.allclose(old.end_pose(world), new.end_pose(world), atol=1e-6)


def test_arms_of_few_joints_get_no_many_joint_budget() -> None:
    world = generate("arm10", 0).world()
    assert world.robot.dof == 10
    ctx = PlanningContext(PlanarSpace(world), PlannerSettings(seed=0), np.random.default_rng(0), Termination(10.0))
    few = _Improver(world, ctx, [], world.object.goal)
    assert few.budget.total == pytest.approx(ctx.settings.improve_time * few.settings.work_per_second)
    snake = generate("snake", 7).world()
    ctx = PlanningContext(PlanarSpace(snake), PlannerSettings(seed=0), np.random.default_rng(0), Termination(10.0))
    many = _Improver(snake, ctx, [], snake.object.goal)
    joints = snake.robot.dof
    expected = ctx.settings.improve_time * many.settings.work_per_second * joints / many.settings.many_budget_joints
    assert many.budget.total == pytest.approx(expected)
