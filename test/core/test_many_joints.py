"""Arms of many joints (issue 46, :class:`~clew_ros.core.settings.ManyJoints`): the straight probes of
SEARCH, and whole runs on the snake family that end with a plan the validator accepts at 0.002 rad."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from clew_ros.core.explore import Explorer
from clew_ros.core.plan import Plan
from clew_ros.core.settings import ManyJoints, Outcome, PlannerSettings, Termination
from clew_ros.core.space import PlanningContext
from clew_ros.core.tree import LandmarkTree
from clew_ros.planar.kernel import warm_up
from clew_ros.planar.plan import replay, validate_plan
from clew_ros.planar.reach import holding_configurations, holding_configurations_near
from clew_ros.planar.search import _moves_clear_stopping, search_transfer
from clew_ros.planar.space import PlanarSpace, plan
from clew_ros.planar.world import World
from clew_ros.worlds import generate


def test_only_arms_of_more_joints_than_the_other_families_are_concerned() -> None:
    assert ManyJoints().straight_probe_joints == 11  # arm10 and every config world plan as before


@pytest.mark.parametrize("seed", [0, 7])
def test_the_transfer_into_the_slot_is_found_from_the_witness_regrasp(seed: int) -> None:
    generated = generate("snake", seed)
    world = generated.world()
    last = list(replay(world, generated.witness, None))[-1]  # the witness's transfer into the slot
    assert last.grasp_rel is not None
    ctx = PlanningContext(PlanarSpace(world), PlannerSettings(seed=0), np.random.default_rng(0), Termination(60.0))
    result = search_transfer(world, ctx, last.configurations[0], last.grasp_rel, world.object.goal)
    assert result.success
    assert ctx.counters.evaluations == 0  # straight moves only: no Manhattan path was decoded


@pytest.mark.parametrize("seed", [2, 7])
def test_a_snake_world_gets_a_valid_plan(seed: int) -> None:
    world = generate("snake", seed).world()
    result = plan(world, PlannerSettings(seed=0, time_limit=60.0))
    assert result.outcome is Outcome.SUCCEEDED, result.message
    assert validate_plan(world, Plan.from_result(world, result), step_rad=0.002) == []


class _CountingTermination(Termination):
    """Says stop from its ``stop_after``-th question on (never when ``None``), counting the questions."""

    def __init__(self, stop_after: int | None) -> None:
        super().__init__(None)
        self.asked = 0
        self.stop_after = stop_after

    def __call__(self) -> bool:
        self.asked += 1
        return self.stop_after is not None and self.asked >= self.stop_after


def _long_clear_move(world: World) -> tuple[np.ndarray, np.ndarray]:
    start = np.asarray(world.robot.initial, float)
    end = start.copy()
    end[:3] += 0.01  # the first three joints, a little: clear of everything from the start posture
    return start[None], end[None]


def test_a_straight_probe_move_is_checked_in_pieces_asking_the_termination_before_each() -> None:
    world = generate("snake", 1).world()
    starts, ends = _long_clear_move(world)
    many = dataclasses.replace(ManyJoints(), check_sweep_m=5e-3)  # pieces of 5 mm sweep: several of them
    running = _CountingTermination(None)
    ctx = PlanningContext(PlanarSpace(world), PlannerSettings(seed=0), np.random.default_rng(0), running, many=many)
    assert _moves_clear_stopping(world, ctx, starts, ends, object_pose=world.object.initial, until=True).all()
    assert running.asked >= 5  # asked before each piece, not once for the whole move
    stopping = _CountingTermination(3)
    ctx = PlanningContext(PlanarSpace(world), PlannerSettings(seed=0), np.random.default_rng(0), stopping, many=many)
    clear = _moves_clear_stopping(world, ctx, starts, ends, object_pose=world.object.initial, until=True)
    assert not clear.any()  # stopped: not proven clear
    assert stopping.asked <= running.asked // 2  # and no piece was checked after the stop


@pytest.mark.parametrize(("world_seed", "planner_seed"), [(1, 1), (5, 0)])
def test_a_many_joint_run_ends_near_its_time_limit(world_seed: int, planner_seed: int) -> None:
    warm_up()  # a liveness bound, not a speed figure: the compiler's time is not the planner's
    world = generate("snake", world_seed).world()
    limit = 2.0
    result = plan(world, PlannerSettings(seed=planner_seed, time_limit=limit))
    if result.outcome is Outcome.TIME_LIMIT:
        assert result.stats["time_s"] <= limit + 2.0, result.stats


@pytest.mark.parametrize("seed", [0, 1])
def test_holds_solved_from_the_arms_own_posture_are_nearer_it_than_random_ones(seed: int) -> None:
    generated = generate("snake", seed)
    world = generated.world()
    first = next(iter(replay(world, generated.witness, None)))  # the witness's first transit: to a grasp at rest
    q0, pose = first.configurations[0], first.object_poses[0]
    near_travel: list[float] = []
    random_travel: list[float] = []
    for g in range(len(world.object.grasps)):
        near = holding_configurations_near(world, q0, pose, g, None, starts=12, spread_rad=0.15)
        drawn = holding_configurations(world, pose, g, 96)
        near_travel += list(np.abs(near - q0).sum(axis=1))
        random_travel += list(np.abs(drawn - q0).sum(axis=1))
    assert near_travel, "no hold solved from the arm's posture"
    assert min(near_travel) < 0.5 * float(np.median(random_travel))


def test_a_many_joint_transfer_decodes_no_manhattan_path_when_its_straight_probe_fails() -> None:
    generated = generate("snake", 0)
    world = generated.world()
    ctx = PlanningContext(PlanarSpace(world), PlannerSettings(seed=0), np.random.default_rng(0), Termination(60.0))
    start = np.asarray(world.robot.initial, float)
    # the object held 5 cm ahead of the tip from the arm's start posture: no straight move puts it in the slot
    result = search_transfer(world, ctx, start, np.array([0.05, 0.0, 0.0]), world.object.goal)
    assert not result.success
    assert ctx.counters.evaluations == 0  # ManyJoints.transfer_ga is off: no GA round


def test_explore_runs_few_generations_on_a_many_joint_arm() -> None:
    world = generate("snake", 3).world()
    ctx = PlanningContext(PlanarSpace(world), PlannerSettings(seed=0), np.random.default_rng(0), Termination(60.0))
    assert ctx.settings.generations > ctx.many.explore_generations
    exploration = Explorer(ctx, LandmarkTree(world.robot.initial, world.object.initial)).explore()
    assert exploration is not None
    size = ctx.settings.population
    # transits decode no Manhattan path on such arms (ManyJoints.transit_ga): every evaluation is EXPLORE's GA
    assert 0 < ctx.counters.evaluations <= size + ctx.many.explore_generations * (size - ctx.settings.genetic.elite)
