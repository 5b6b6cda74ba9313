"""SEARCH_TRANSIT's direct straight moves from ``ManyJoints.straight_transit_joints`` (7) joints (issue 57): a
transit whose straight move to a hold is clear decodes no Manhattan path; one whose straight moves are blocked
still runs the greedy probe and the GA; arms of fewer joints plan as before (no straight targets)."""

from __future__ import annotations

import numpy as np
import pytest

from clew_ros.core.search import SearchJob, local_search
from clew_ros.core.settings import ManyJoints, PlannerSettings, Termination
from clew_ros.core.space import Mode, PlanningContext
from clew_ros.planar import search as planar_search
from clew_ros.planar.collision import is_valid
from clew_ros.planar.continuous import path_valid, straight_moves_clear
from clew_ros.planar.space import PlanarSpace
from clew_ros.planar.world import World
from clew_ros.worlds import generate


def _context(world: World, seed: int = 0) -> PlanningContext:
    settings = PlannerSettings(seed=seed)
    return PlanningContext(PlanarSpace(world), settings, np.random.default_rng(seed), Termination(30.0))


def _job(world: World, start: np.ndarray, goal: np.ndarray) -> SearchJob:
    """A transit to the configuration ``goal`` (the OMPL peer's problem), with it as straight target."""
    mode = Mode.resting(np.asarray(world.object.initial, float)[None])

    def objective(q: np.ndarray, _poses: np.ndarray) -> np.ndarray:
        distance: np.ndarray = 0.1 * np.linalg.norm(q - goal, axis=1)
        return distance

    def error(q: np.ndarray) -> np.ndarray:
        return 0.1 * (q - goal)

    return SearchJob(start, objective, error, 1e-5, mode, toward=goal, straight=goal[None])


def _pairs(world: World, clear: bool, count: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """``count`` pairs of valid configurations 1 rad or more apart whose straight move is (or is not) clear."""
    rng = np.random.default_rng(seed)
    lower, upper = world.robot.joint_lower, world.robot.joint_upper
    pose = np.asarray(world.object.initial, float)
    found: list[tuple[np.ndarray, np.ndarray]] = []
    while len(found) < count:
        a, b = rng.uniform(lower, upper, size=(2, len(lower)))
        if np.linalg.norm(a - b) < 1.0 or not is_valid(world, np.array([a, b]), np.array([pose, pose])).all():
            continue
        ok = straight_moves_clear(world, a[None], b[None], object_pose=pose, min_margin=0.0)[0]
        if bool(ok) == clear:
            found.append((a, b))
    return found


def test_the_straight_transit_starts_at_seven_joints_below_the_many_joint_adaptations() -> None:
    many = ManyJoints()
    assert many.straight_transit_joints == 7 < many.straight_probe_joints


def test_a_seven_joint_transit_with_a_clear_straight_move_decodes_no_manhattan_path() -> None:
    world = generate("arm7", 0).world()
    assert world.robot.dof == 7
    for start, goal in _pairs(world, clear=True, count=3, seed=1):
        ctx = _context(world)
        [(waypoints, distance)] = local_search(ctx, [_job(world, start, goal)])
        assert distance == pytest.approx(0.0, abs=1e-12)
        assert ctx.counters.evaluations == 0  # neither the greedy probe nor the GA
        assert np.array_equal(waypoints, np.array([start, goal]))
        assert path_valid(world, waypoints, object_pose=np.asarray(world.object.initial, float))


def test_a_seven_joint_transit_whose_straight_move_is_blocked_still_searches() -> None:
    world = generate("arm7", 0).world()
    [(start, goal), _] = _pairs(world, clear=False, count=2, seed=2)
    ctx = _context(world)
    [(waypoints, distance)] = local_search(ctx, [_job(world, start, goal)])
    # the greedy probe, then the GA rounds (ManyJoints.transit_ga is off only from 11 joints) and refinement
    assert ctx.counters.evaluations > 1
    assert distance < 1e-5
    assert np.array_equal(waypoints[0], start)
    assert path_valid(world, waypoints, object_pose=np.asarray(world.object.initial, float))


@pytest.mark.parametrize(("family", "straight"), [("window", False), ("arm7", True), ("arm10", True)])
def test_only_transits_of_seven_joints_or_more_get_straight_targets(
    family: str, straight: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    world = generate(family, 0).world()
    seen: list[SearchJob] = []

    def recording(ctx: PlanningContext, jobs: list[SearchJob]) -> list[tuple[np.ndarray, float]]:
        seen.extend(jobs)
        return local_search(ctx, jobs)

    monkeypatch.setattr(planar_search, "local_search", recording)
    ctx = _context(world)
    start = np.asarray(world.robot.initial, float)
    for grasp in range(len(world.object.grasps)):
        planar_search.search_transit(world, ctx, start, np.asarray(world.object.initial, float), grasp=grasp)
    assert seen, "no transit got as far as SEARCH"
    assert all((job.straight is not None) == straight for job in seen)
    if straight:
        assert all(1 <= len(job.straight) <= ManyJoints().straight_probes for job in seen if job.straight is not None)
