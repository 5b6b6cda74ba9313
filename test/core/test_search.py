"""SEARCH_TRANSIT and SEARCH_TRANSFER (paper 1.3.2, 1.3.4) as local planners, checked by replaying their paths."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from clew_ros.core.settings import PlannerSettings, SearchSettings
from clew_ros.core.space import Mode, PlanningContext
from clew_ros.planar.collision import is_valid
from clew_ros.planar.kinematics import compose, tip_poses, transform_points
from clew_ros.planar.plan import interpolate
from clew_ros.planar.search import goal_error, goal_reached, search_transfer, search_transit
from clew_ros.planar.space import PlanarSpace
from clew_ros.planar.world import load_world

QUICK = Path(__file__).parents[1] / "worlds" / "node_quick.yaml"


@pytest.fixture(scope="module")
def world():
    return load_world(QUICK)


def context(world, seed: int = 0) -> PlanningContext:
    return PlanningContext(PlanarSpace(world), PlannerSettings(seed=seed), np.random.default_rng(seed))


def test_search_transit_reaches_a_grasp_without_touching_the_resting_object(world) -> None:
    pose = world.object.initial
    result = search_transit(world, context(world), world.robot.initial, pose, grasp=1)
    assert result.success
    target = transform_points(pose, world.object.grasps[1][None])[0]
    tip = tip_poses(world.robot, result.waypoints[-1:])[0]
    assert np.linalg.norm(tip[:2] - target) <= world.grasp_tolerance
    assert np.allclose(compose(tip[None], result.grasp_rel[None])[0], pose)  # the held pose is where it rests
    assert np.array_equal(result.waypoints[0], world.robot.initial)
    assert np.all(np.count_nonzero(np.diff(result.waypoints, axis=0), axis=1) <= 1)  # Manhattan moves
    configurations = interpolate(result.waypoints, 0.002)
    assert is_valid(world, configurations, pose).all()


def test_search_transfer_carries_the_object_to_the_goal(world) -> None:
    ctx = context(world)
    transit = search_transit(world, ctx, world.robot.initial, world.object.initial, grasp=1)
    assert transit.success
    goal = world.object.goal
    result = search_transfer(world, ctx, transit.waypoints[-1], transit.grasp_rel, goal)
    assert result.success
    assert goal_reached(world, result.object_pose, goal)
    configurations = interpolate(result.waypoints, 0.002)
    poses = compose(tip_poses(world.robot, configurations), transit.grasp_rel[None])
    assert is_valid(world, configurations, poses).all()
    assert np.allclose(poses[-1], result.object_pose)


def test_same_seed_same_path_and_an_unreachable_goal_fails_without_searching(world) -> None:
    first = search_transit(world, context(world, 3), world.robot.initial, world.object.initial, grasp=0)
    again = search_transit(world, context(world, 3), world.robot.initial, world.object.initial, grasp=0)
    assert np.array_equal(first.waypoints, again.waypoints)
    far = np.array([5.0, 5.0, 0.0])
    ctx = context(world)
    result = search_transfer(world, ctx, first.waypoints[-1], first.grasp_rel, far)
    assert not result.success
    assert len(result.waypoints) == 1
    assert ctx.counters.evaluations == 0


def test_goal_error_is_zero_at_the_goal_and_counts_only_excess_angle(world) -> None:
    goal = np.array([0.5, 0.5, 0.0])
    assert np.allclose(goal_error(world, goal[None], goal), 0.0)
    turned = goal + np.array([0.0, 0.0, 0.5 * world.goal_angle_tolerance])
    assert np.allclose(goal_error(world, turned[None], goal), 0.0)  # inside the angle slack
    moved = goal + np.array([0.03, -0.04, 0.0])
    assert np.isclose(np.linalg.norm(goal_error(world, moved[None], goal)), 0.05)


def _joint_space_job(world, q0: np.ndarray, goal: np.ndarray):
    from clew_ros.core.search import SearchJob

    return SearchJob(
        q0,
        lambda q, _poses: 0.1 * np.linalg.norm(q - goal, axis=1),
        lambda q: 0.1 * (q - goal),
        1e-5,
        Mode.resting(world.object.initial[None]),
        toward=goal,
    )


def test_greedy_probe_takes_an_open_way_without_a_generation_and_is_off_on_request(world, monkeypatch) -> None:
    from clew_ros.core import search

    q0 = np.asarray(world.robot.initial, float)
    goal = q0 + np.array([-0.8, 0.6])
    assert is_valid(world, interpolate(np.array([q0, [goal[0], q0[1]], goal]), 0.002), world.object.initial).all()
    ctx = context(world)
    [(waypoints, distance)] = search.local_search(ctx, [_joint_space_job(world, q0, goal)])
    assert ctx.counters.evaluations == 1  # the probe alone: no GA population was decoded
    assert distance <= 1e-5
    assert np.allclose(waypoints[-1], goal, atol=1e-3)
    assert np.all(np.count_nonzero(np.diff(waypoints, axis=0), axis=1) <= 1)  # still Manhattan moves
    ctx = dataclasses.replace(context(world), search=SearchSettings(greedy_probe=False))
    search.local_search(ctx, [_joint_space_job(world, q0, goal)])
    assert ctx.counters.evaluations > 1


def test_greedy_probe_into_an_obstacle_stops_short_and_stays_valid(world, monkeypatch) -> None:
    """The probe alone (the GA finds nothing better, no refinement): never farther, always valid."""
    from types import SimpleNamespace

    from clew_ros.core import search

    def no_progress(_evaluate, initial, *_args, **_kwargs):
        return [SimpleNamespace(fitness=np.inf, genes=None) for _ in initial]

    monkeypatch.setattr(search, "minimize_islands", no_progress)
    monkeypatch.setattr(search, "_refine", lambda _ctx, q, *_args, **_kwargs: q[None])
    q0 = np.asarray(world.robot.initial, float)
    rng = np.random.default_rng(5)
    short = 0
    for _ in range(20):  # goals across the joint space: the probe's straight moves often meet something
        goal = rng.uniform(world.robot.joint_lower, world.robot.joint_upper)
        job = _joint_space_job(world, q0, goal)
        before = float(job.objective(q0[None], None)[0])
        [(path, distance)] = search.local_search(context(world), [job])
        assert distance <= before  # never farther
        assert is_valid(world, interpolate(path, 0.002), world.object.initial).all()
        short += distance > 1e-3
    assert short  # some probes did meet an obstacle


def test_transfer_probe_heads_for_a_configuration_holding_the_object_at_the_goal(world, monkeypatch) -> None:
    from clew_ros.planar import search

    ctx = context(world)
    transit = search_transit(world, ctx, world.robot.initial, world.object.initial, grasp=1)
    assert transit.success
    q0, goal = transit.waypoints[-1], world.object.goal
    state = ctx.rng.bit_generator.state
    toward = search.transfer_probe_target(world, ctx, q0, transit.grasp_rel, goal)
    assert ctx.rng.bit_generator.state == state  # drawn from a generator of its own: the run's stream is as it was
    assert toward is not None
    pose = compose(tip_poses(world.robot, toward[None]), transit.grasp_rel[None])[0]
    assert goal_reached(world, pose, goal)
    assert is_valid(world, toward[None], pose[None]).all()
    again = search.transfer_probe_target(world, context(world), q0, transit.grasp_rel, goal)
    assert again is not None
    assert np.array_equal(toward, again)  # same request, same target
    off = dataclasses.replace(ctx, search=SearchSettings(transfer_probe=False))
    assert search.transfer_probe_target(world, off, q0, transit.grasp_rel, goal) is None
