"""SEARCH_TRANSFER's way in (search.goal_configurations, connect.join) and RRT-Connect (core.connect): goal
configurations hold the object within the goal's tolerances; a joined path starts where the search
stalled, ends at the goal, is valid at a step ten times finer than the validator's and is the same
from the same generator."""

from __future__ import annotations

import functools
import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from clew_ros.core.settings import PlannerSettings, SearchSettings
from clew_ros.planar.collision import is_valid
from clew_ros.planar.connect import ConnectSettings, join, rrt_connect, shortened
from clew_ros.planar.continuous import ContinuousSettings, straight_move_clear
from clew_ros.planar.kinematics import compose, tip_poses
from clew_ros.planar.plan import replay
from clew_ros.planar.search import goal_configurations, goal_reached
from clew_ros.planar.world import load_world
from clew_ros.worlds import generate

ROOT = Path(__file__).resolve().parents[2]
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
            min_margin=ContinuousSettings().min_margin_factor * PlannerSettings().clearance,
            rounds=SearchSettings().join_rounds,
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


class _Routing:
    """A routing budget (``connect.RoutingBudget``) that records what is spent and stops when told."""

    check_work = 1.0
    round_work = 2.0

    def __init__(self, allowance: float = math.inf, stopped: bool = False) -> None:
        self.left = allowance
        self.stopped = stopped
        self.spent: list[float] = []

    def allowance(self) -> float:
        return self.left - sum(self.spent)

    def spend(self, units: float) -> None:
        self.spent.append(units)

    def stop(self) -> bool:
        return self.stopped


def _blocked_move(world, rng: np.random.Generator, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """Two valid configurations (the object at rest) whose straight move is not clear."""
    rest = np.asarray(world.object.initial, dtype=float)
    while True:
        a, b = rng.uniform(world.robot.joint_lower, world.robot.joint_upper, (2, world.robot.dof))
        if is_valid(world, np.stack([a, b]), rest).all() and not straight_move_clear(
            world, a, b, object_pose=rest, min_margin=margin
        ):
            return a, b


def test_rrt_connect_goes_round_an_obstacle_to_one_of_several_goals() -> None:
    world = load_world(ROOT / "config" / "figure1.yaml")
    rest = np.asarray(world.object.initial, dtype=float)
    margin = ContinuousSettings().min_margin_factor * PlannerSettings().clearance
    routed = fine_routed = 0
    for trial in range(3):
        start, goal = _blocked_move(world, np.random.default_rng(trial), margin)
        goals = np.stack([goal, np.clip(goal + 0.05, world.robot.joint_lower, world.robot.joint_upper)])
        budgets = [_Routing(), _Routing()]
        paths = [
            rrt_connect(world, start, goals, np.random.default_rng(3), object_pose=rest, min_margin=margin,
                        rounds=2000, budget=budget)
            for budget in budgets
        ]  # fmt: skip
        if paths[0] is None:
            continue
        routed += 1
        assert paths[1] is not None
        assert np.array_equal(paths[0], paths[1])
        assert budgets[0].spent == budgets[1].spent
        assert sum(budgets[0].spent) > 0
        path = paths[0]
        assert np.array_equal(path[0], start)
        assert any(np.array_equal(path[-1], g) for g in goals)
        assert (
            np.max(np.abs(np.diff(path, axis=0))) <= ConnectSettings().step_rad + 1e-12
        )  # one step per extension at most
        assert all(
            straight_move_clear(world, u, v, object_pose=rest, min_margin=margin) for u, v in itertools.pairwise(path)
        )
        assert is_valid(world, _fine(path), rest).all()
        short = shortened(lambda u, v: straight_move_clear(world, u, v, object_pose=rest, min_margin=margin), path)
        assert np.array_equal(short[0], path[0])
        assert np.array_equal(short[-1], path[-1])
        assert is_valid(world, _fine(short), rest).all()
        assert len(short) <= len(path)
        fine = rrt_connect(world, start, goals, np.random.default_rng(3), object_pose=rest, min_margin=margin,
                           rounds=4000, budget=_Routing(), settings=ConnectSettings(step_rad=0.1))  # fmt: skip
        if fine is not None:  # a copy of the settings: shorter extensions
            fine_routed += 1
            assert np.max(np.abs(np.diff(fine, axis=0))) <= 0.1 + 1e-12
    assert routed >= 2
    assert fine_routed >= 1


def test_rrt_connect_gives_up_when_stopped_walled_in_or_out_of_work() -> None:
    world = load_world(ROOT / "config" / "figure1.yaml")
    rest = np.asarray(world.object.initial, dtype=float)
    margin = ContinuousSettings().min_margin_factor * PlannerSettings().clearance
    start, goal = _blocked_move(world, np.random.default_rng(0), margin)
    route = functools.partial(rrt_connect, world, start, object_pose=rest, rounds=400)
    assert route(goals=goal[None], rng=np.random.default_rng(0), min_margin=margin, budget=_Routing()) is not None
    stopped = _Routing(stopped=True)
    assert route(goals=goal[None], rng=np.random.default_rng(0), min_margin=margin, budget=stopped) is None
    assert stopped.spent == []
    walled_in = _Routing()  # nothing keeps 10 m from everything: no move is clear
    assert route(goals=goal[None], rng=np.random.default_rng(0), min_margin=10.0, budget=walled_in) is None
    assert len(walled_in.spent) == math.ceil(400 / ConnectSettings().rounds_per_call)  # every round was tried
    one_round = _Routing(allowance=1e-9)  # the first round passes it: no second round starts
    assert route(goals=goal[None], rng=np.random.default_rng(0), min_margin=margin, budget=one_round) is None
    short = _Routing(allowance=50.0)
    assert route(goals=goal[None], rng=np.random.default_rng(0), min_margin=margin, budget=short) is None
    assert len(one_round.spent) == len(short.spent) == 1
    assert 0 < one_round.spent[0] < 50.0 <= short.spent[0]  # the rounds went on until the allowance was spent
    with pytest.raises(ValueError, match="goals"):
        route(goals=np.zeros((0, 2)), rng=np.random.default_rng(0), min_margin=margin, budget=_Routing())


def test_a_join_that_fails_leaves_the_run_as_it_was(monkeypatch) -> None:
    """Joins draw from a generator of their own: a run whose joins all fail plans exactly what it plans with
    no joins at all; a run whose join succeeds gives a valid plan."""
    from clew_ros.core.plan import Plan
    from clew_ros.planar import search
    from clew_ros.planar.plan import validate_plan
    from clew_ros.planar.space import PlanarTuning, plan

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
        plain = plan(world, settings, tuning=PlanarTuning(search=SearchSettings(join_radius=0.0)))
        assert [np.asarray(s.waypoints).tolist() for s in joined.segments] == [
            np.asarray(s.waypoints).tolist() for s in plain.segments
        ]
        assert joined.stats["landmarks"] == plain.stats["landmarks"]
    assert branches == {"failed", "succeeded"}
