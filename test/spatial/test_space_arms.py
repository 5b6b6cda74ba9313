"""clew_ros.spatial.space on random arms of few joints (``clew_world spatial_* --robot random``): where no
configuration holds a placement's whole pose, the object is set down level, and the pick-and-place is
planned and valid at the validator's 0.002 rad."""

from __future__ import annotations

import numpy as np
import pytest

from clew_ros.core.settings import PlannerSettings
from clew_ros.spatial.offline import checked_plan
from clew_ros.spatial.space import SpatialSpace, SpatialTuning, plan
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
        assert not any(space.rests(pose) for pose in space.held_object_poses(lifted, rel))
        settled, ok = space.settle(space.transfer_checker(rel), rel, lifted)
        assert ok.all() if level else not ok.any()
        for q, start in zip(settled[ok], lifted[ok], strict=True):
            assert space.rests(space.held_object_poses(q[None], rel)[0])
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
