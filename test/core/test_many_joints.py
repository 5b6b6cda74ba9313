"""Arms of many joints (issue 46, :class:`~clew_ros.core.settings.ManyJoints`): the straight probes of
SEARCH, and whole runs on the snake family that end with a plan the validator accepts at 0.002 rad."""

from __future__ import annotations

import numpy as np
import pytest

from clew_ros.core.clew import plan
from clew_ros.core.plan import Plan, replay, validate_plan
from clew_ros.core.search import PlanningContext, search_transfer
from clew_ros.core.settings import ManyJoints, Outcome, PlannerSettings, Termination
from clew_ros.worlds import generate


def test_only_arms_of_more_joints_than_the_other_families_are_concerned() -> None:
    assert ManyJoints().straight_probe_joints == 11  # arm10 and every config world plan as before


@pytest.mark.parametrize("seed", [0, 7])
def test_the_transfer_into_the_slot_is_found_from_the_witness_regrasp(seed: int) -> None:
    generated = generate("snake", seed)
    world = generated.world()
    last = list(replay(world, generated.witness, None))[-1]  # the witness's transfer into the slot
    assert last.grasp_rel is not None
    ctx = PlanningContext(world, PlannerSettings(seed=0), np.random.default_rng(0), Termination(60.0))
    result = search_transfer(ctx, last.configurations[0], last.grasp_rel, world.object.goal)
    assert result.success
    assert ctx.counters.evaluations == 0  # straight moves only: no Manhattan path was decoded


@pytest.mark.parametrize("seed", [2, 7])
def test_a_snake_world_gets_a_valid_plan(seed: int) -> None:
    world = generate("snake", seed).world()
    result = plan(world, PlannerSettings(seed=0, time_limit=60.0))
    assert result.outcome is Outcome.SUCCEEDED, result.message
    assert validate_plan(world, Plan.from_result(world, result), step_rad=0.002) == []
