"""SEARCH_TRANSFER's way in (search.goal_configurations, connect.join) and RRT-Connect (core.connect): goal
configurations hold the object within the goal's tolerances; a joined path starts where the search
stalled, ends at the goal, is valid at a step ten times finer than the validator's and is the same
from the same generator."""

from __future__ import annotations

import itertools

import numpy as np

from clew_ros.core.collision import is_valid
from clew_ros.core.connect import join, rrt_connect, shortened
from clew_ros.core.continuous import MIN_MARGIN_FACTOR
from clew_ros.core.kinematics import compose, tip_poses
from clew_ros.core.plan import replay
from clew_ros.core.search import JOIN_ROUNDS, goal_configurations, goal_reached
from clew_ros.core.settings import PlannerSettings
from clew_ros.worlds import generate

FINE_RAD = 2e-4  # ten times finer than the validator


def _fine(path: np.ndarray) -> np.ndarray:
    pieces = [path[:1]]
    for u, v in itertools.pairwise(path):
        steps = max(1, int(np.ceil(np.max(np.abs(v - u)) / FINE_RAD)))
        pieces.append(u + np.linspace(0.0, 1.0, steps + 1)[1:, None] * (v - u))
    return np.concatenate(pieces)


def _last_transfer(family: str, seed: int):
    """A generated world and its witness's last transfer: the object held as ``grasp_rel`` from the
    transfer's waypoints ``q`` (``(m, n)``) to the goal."""
    generated = generate(family, seed)
    world = generated.world()
    motion = [m for m in replay(world, generated.witness, step_rad=None) if m.kind == "transfer"][-1]
    return world, motion.configurations, motion.grasp_rel


CASES = [("pocket", s) for s in range(4)] + [("clutter", s) for s in range(3)] + [("arm7", 0), ("shelves", 1)]


def _joined(family: str, seed: int) -> bool:
    """Goal configurations and a joined path from where the witness starts its last transfer (a way in
    exists), with every property checked; whether a path was found within the rounds allowed."""
    world, q, grasp_rel = _last_transfer(family, seed)
    goal = np.asarray(world.object.goal, dtype=float)
    stalled = q[0]
    goals = goal_configurations(world, stalled, grasp_rel, goal, np.random.default_rng(seed))
    assert len(goals), f"{family}_{seed}"  # the goal's own angle from the witness's posture
    poses = compose(tip_poses(world.robot, goals), grasp_rel)
    assert all(goal_reached(world, pose, goal) for pose in poses)
    assert is_valid(world, goals, poses).all()
    assert np.all(goals >= world.robot.joint_lower)
    assert np.all(goals <= world.robot.joint_upper)
    gaps = np.max(np.abs(goals - stalled), axis=1)
    assert np.all(np.diff(gaps) >= 0)  # nearest first

    def join_goal() -> np.ndarray | None:
        return join(
            world,
            stalled,
            goals,
            np.random.default_rng(seed),
            grasp_rel=grasp_rel,
            min_margin=MIN_MARGIN_FACTOR * PlannerSettings().clearance,
            rounds=JOIN_ROUNDS,
            stop=lambda: False,
        )

    path, again = join_goal(), join_goal()
    if path is None:
        assert again is None
        return False
    assert again is not None
    assert np.array_equal(path, again)  # the same generator, the same path
    assert np.array_equal(path[0], stalled)
    assert goal_reached(world, compose(tip_poses(world.robot, path[-1:]), grasp_rel)[0], goal)
    fine = _fine(path)
    assert is_valid(world, fine, compose(tip_poses(world.robot, fine), grasp_rel)).all()
    return True


def test_joining_the_goal_from_the_witness_s_last_transfer() -> None:
    joined = [_joined(family, seed) for family, seed in CASES]
    assert sum(joined) >= 6, joined  # 7 of 9 when written; each join is bounded, so some may fail


def test_no_goal_configuration_when_the_grasp_cannot_hold_the_object_at_the_goal() -> None:
    world, q, grasp_rel = _last_transfer("pocket", 0)
    far = np.array([grasp_rel[0] + 10.0, grasp_rel[1], grasp_rel[2]])  # the object held 10 m beyond the tip
    goal = np.asarray(world.object.goal, float)
    assert len(goal_configurations(world, q[0], far, goal, np.random.default_rng(0))) == 0


def _disc_clear(centre: np.ndarray, radius: float):
    """A straight move between 2-D points is clear when it keeps out of a disc (exact segment test)."""

    def clear(a: np.ndarray, b: np.ndarray) -> bool:
        d = b - a
        t = 0.0 if not d.any() else float(np.clip((centre - a) @ d / (d @ d), 0.0, 1.0))
        return float(np.linalg.norm(a + t * d - centre)) > radius

    return clear


def test_rrt_connect_goes_round_a_wall_to_the_nearest_of_several_goals() -> None:
    clear = _disc_clear(np.zeros(2), 1.0)
    start = np.array([-1.5, 0.0])
    goals = np.array([[1.5, 0.1], [1.6, -0.2]])
    limits = (np.full(2, -3.0), np.full(2, 3.0))
    paths = [
        rrt_connect(clear, start, goals, np.random.default_rng(3), limits=limits, rounds=400, stop=lambda: False)
        for _ in range(2)
    ]
    assert paths[0] is not None
    assert np.array_equal(paths[0], paths[1])
    path = paths[0]
    assert np.array_equal(path[0], start)
    assert any(np.array_equal(path[-1], g) for g in goals)
    assert all(clear(u, v) for u, v in itertools.pairwise(path))
    assert np.max(np.abs(np.diff(path, axis=0))) <= 0.35 + 1e-12  # one step per extension at most
    short = shortened(clear, path)
    assert np.array_equal(short[0], path[0])
    assert np.array_equal(short[-1], path[-1])
    assert all(clear(u, v) for u, v in itertools.pairwise(short))
    assert len(short) <= len(path)


def test_rrt_connect_gives_up_when_stopped_or_walled_in() -> None:
    limits = (np.full(2, -3.0), np.full(2, 3.0))
    start, goal = np.array([-1.5, 0.0]), np.array([[1.5, 0.0]])
    never = lambda a, b: False  # noqa: E731 - nothing is clear
    assert (
        rrt_connect(never, start, goal, np.random.default_rng(0), limits=limits, rounds=50, stop=lambda: False) is None
    )
    clear = _disc_clear(np.zeros(2), 1.0)
    assert (
        rrt_connect(clear, start, goal, np.random.default_rng(0), limits=limits, rounds=50, stop=lambda: True) is None
    )


def test_a_join_that_fails_leaves_the_run_as_it_was(monkeypatch) -> None:
    """Joins draw from a generator of their own: a run whose joins all fail plans exactly what it plans with
    no joins at all; a run whose join succeeds gives a valid plan."""
    from clew_ros.core import search
    from clew_ros.core.clew import plan
    from clew_ros.core.plan import Plan, validate_plan

    calls: list[bool] = []
    real_join = search.join

    def counted(*args, **kwargs):
        path = real_join(*args, **kwargs)
        calls.append(path is not None)
        return path

    branches = set()
    # (family, world seed, planner seed): joins that all fail, then joins that succeed (when written)
    for family, world_seed, seed in [("clutter", 3, 0), ("pocket", 0, 1), ("clutter", 0, 0), ("pocket", 3, 1)]:
        world = generate(family, world_seed).world()
        settings = PlannerSettings(seed=seed, time_limit=60, improve_time=0.0)
        calls.clear()
        monkeypatch.setattr(search, "join", counted)
        joined = plan(world, settings)
        monkeypatch.undo()
        assert calls, f"{family}_{world_seed}: no join tried"
        assert joined.success
        assert validate_plan(world, Plan.from_result(world, joined)) == []
        if any(calls):
            branches.add("succeeded")
            continue
        branches.add("failed")
        monkeypatch.setattr(search, "JOIN_RADIUS", 0.0)
        plain = plan(world, settings)
        monkeypatch.undo()
        assert [np.asarray(s.waypoints).tolist() for s in joined.segments] == [
            np.asarray(s.waypoints).tolist() for s in plain.segments
        ]
        assert joined.stats["landmarks"] == plain.stats["landmarks"]
    assert branches == {"failed", "succeeded"}
