"""clew_ros.spatial.space on random arms of few joints (``clew_world spatial_* --robot random``): where no
configuration holds a placement's whole pose, the object is set down level, and the pick-and-place is
planned and valid at the validator's 0.002 rad."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from clew_ros.core.settings import PlannerSettings, Termination
from clew_ros.core.space import PlanningContext
from clew_ros.spatial.distances import at_goal
from clew_ros.spatial.offline import checked_plan
from clew_ros.spatial.search import goal_tree, transfer_trees
from clew_ros.spatial.settle import rests, settle
from clew_ros.spatial.space import SpatialSpace, SpatialTuning, plan
from clew_ros.spatial.targets import goal_configurations
from clew_ros.spatial.validate import ValidationSettings, validation_samples
from clew_ros.worlds.spatial import generate_spatial


@pytest.mark.parametrize(("family", "world_seed"), [("spatial_table", 5), ("spatial_reorient", 5)])
def test_a_lifted_object_is_set_down_level_by_an_arm_of_few_joints(family: str, world_seed: int) -> None:
    """The witness's first configurations lifting the object (an arm of 4-5 joints): the placement below
    them at the same x, y and yaw is out of the arm's reach, the level one beside it is not."""
    generated = generate_spatial(family, world_seed, "random")
    world = generated.world()
    assert world.robot.dof <= 5
    transfer = next(s for s in generated.witness.segments if s.kind == "transfer")
    assert transfer.grasp is not None
    lifted = np.array(transfer.waypoints)[1:4]
    for level in (True, False):
        space = SpatialSpace(world, SpatialTuning(level_settle=level))
        rel = space.grasp_rel(transfer.grasp)
        assert not any(rests(world, pose) for pose in space.held_object_poses(lifted, rel))
        settled, ok = settle(space.parts, space.transfer_checker(rel), rel, lifted)
        assert ok.all() if level else not ok.any()
        for q, start in zip(settled[ok], lifted[ok], strict=True):
            assert rests(world, space.held_object_poses(q[None], rel)[0])
            assert np.max(np.abs(q - start)) <= space.tuning.settle_max_rad


def test_a_pick_and_place_by_an_arm_of_four_joints_is_planned_and_valid() -> None:
    """A reorientation on a 4-joint arm (its approaches by position alone, its transfer set down level):
    planned, and the plan passes the validator (the grasp held, the object resting, the goal reached)."""
    world = generate_spatial("spatial_reorient", 5, "random").world()
    assert world.robot.dof == 4
    result = plan(world, PlannerSettings(seed=0, time_limit=60.0))
    assert result.success, result.message
    checked = checked_plan(world, result)
    assert checked.success, checked.message
    assert sum(s.kind == "transfer" for s in result.segments) == 1


def test_a_failed_transfers_two_trees_carry_the_object_out_of_one_shelf_into_another() -> None:
    """EXPLORE for transfer paths (``spatial.search.transfer_trees``): from the witness's grasp in one narrow
    shelf, the two trees (rooted there and at a goal configuration) find a path whose every piece is valid
    at the validator's 0.002 rad with the object held, and which sets it down at the goal; the goal tree is
    kept for the next SEARCH_TRANSFER of the same grasp and goal, which grows it further; with no
    landmarks to spend there is no such search."""
    world = generate_spatial("spatial_narrow", 12, "panda").world()
    assert world.object is not None
    generated = generate_spatial("spatial_narrow", 12, "panda")
    transfer = next(s for s in generated.witness.segments if s.kind == "transfer")
    assert transfer.grasp is not None
    q0 = np.array(transfer.waypoints[0])
    goal = np.array(world.object.goal)
    settings = PlannerSettings(seed=0, time_limit=60.0)
    space = SpatialSpace(world)
    rel = space.grasp_rel(transfer.grasp)
    ctx = PlanningContext(space, settings, np.random.default_rng(0), Termination(60.0), many=space.tuning.many)
    found = goal_configurations(space.parts, ctx, q0, rel, goal)
    assert len(found)
    for _ in range(10):  # SEARCH_TRANSFERs from the same landmark: the goal tree grows from one to the next
        path = transfer_trees(space, ctx, q0, rel, goal, found=found)
        if path is not None:
            break
    assert path is not None
    assert np.array_equal(path[0], q0)
    assert at_goal(space.parts, space.held_object_poses(path[-1:], rel)[0], goal)
    checker = space.transfer_checker(rel)
    steps = np.full(space.dof, ValidationSettings().step_rad)
    assert all(checker.valid(validation_samples(a, b, steps)).all() for a, b in itertools.pairwise(path))

    grown = SpatialSpace(world, SpatialTuning(transfer_tree_landmarks=2))
    before = 0
    for _ in range(3):
        transfer_trees(grown, ctx, q0 + 0.0, rel, goal, found=found)
        tree = goal_tree(grown.parts, rel, goal)
        assert tree is not None
        assert len(tree) >= before
        before = len(tree)
    assert before > 1
    none = SpatialSpace(world, SpatialTuning(transfer_tree_landmarks=0))
    assert transfer_trees(none, ctx, q0, rel, goal, found=found) is None
