"""Anytime improvement (issue 14): never invalid, never longer, never more transfers; deterministic;
cancel returns the best plan so far; ``improve_time: 0`` gives the first plan."""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np
import pytest
from helpers.open_reach import open_reach
from helpers.paths import random_path
from helpers.random_boxes import random_box_world

from clew_ros.core.clew import IMPROVE_STREAM
from clew_ros.core.improve import joined_regrasps, joint_travel, pruned_path
from clew_ros.core.plan import Plan, PlanSegment
from clew_ros.core.settings import Outcome, PlannerSettings, Termination
from clew_ros.core.space import PlanningContext
from clew_ros.core.tree import Segment
from clew_ros.planar.collision import is_valid
from clew_ros.planar.continuous import straight_move_clear, straight_moves_clear
from clew_ros.planar.improve import ImproveSettings, _Improver, _Piece, _pieces, improve
from clew_ros.planar.inverse import solve_point
from clew_ros.planar.kinematics import compose, relative, tip_poses
from clew_ros.planar.manhattan import run_manhattan
from clew_ros.planar.plan import replay, validate_plan
from clew_ros.planar.regrasp import goal_holds_near
from clew_ros.planar.space import PlanarSpace, plan
from clew_ros.planar.world import load_world, world_from_parameters

ROOT = Path(__file__).resolve().parents[2]
FINE_RAD = 2e-4  # ten times finer than the validator


def _world(name: str):
    path = ROOT / "config" / f"{name}.yaml"
    return load_world(path if path.exists() else ROOT / "test" / "worlds" / f"{name}.yaml")


def _plan(world, seed: int, improve_time: float, **settings):
    return plan(world, PlannerSettings(seed=seed, time_limit=60, improve_time=improve_time, **settings))


CASES = [("figure1", 0), ("figure1", 3), ("arm3_regrasp", 1), ("single_transfer", 2), ("node_quick", 0)]


@pytest.mark.parametrize(("name", "seed"), CASES, ids=[f"{n}_seed{s}" for n, s in CASES])
def test_improvement_keeps_the_plan_valid_and_never_makes_it_longer(name, seed) -> None:
    world = _world(name)
    first = _plan(world, seed, 0.0)
    better = _plan(world, seed, 0.3)
    assert first.success
    assert better.success
    assert better.stats["first_joint_travel_rad"] == first.stats["joint_travel_rad"]
    assert better.stats["first_transfers"] == first.stats["transfers"]
    travel = joint_travel(better.segments)
    transfers = sum(s.kind == "transfer" for s in better.segments)
    assert better.stats["joint_travel_rad"] == pytest.approx(travel, abs=1e-6)
    assert better.stats["transfers"] == transfers
    assert transfers <= first.stats["transfers"]
    assert travel <= joint_travel(first.segments) + 1e-9
    improved = Plan.from_result(world, better)
    assert validate_plan(world, improved) == []
    # valid at a much finer check too: the shortcuts keep a clearance, they are not only sampled
    for motion in replay(world, improved, FINE_RAD):
        assert is_valid(world, motion.configurations, motion.object_poses).all()


FIGURE1_REFERENCE_RAD = 5.46  # python -m benchmarks.reference --worlds figure1


def test_improvement_gains_on_figure1_and_is_deterministic() -> None:
    world = _world("figure1")
    a = _plan(world, 0, 0.3)
    b = _plan(world, 0, 0.3)
    # shorter, and near the brute-force grid reference's 5.46 rad (docs/benchmarks.md, "Plan quality against
    # the grid reference"): issue 14's 2-joint target is at most 1.3x
    assert a.stats["joint_travel_rad"] < a.stats["first_joint_travel_rad"] - 0.5
    assert a.stats["joint_travel_rad"] <= 1.3 * FIGURE1_REFERENCE_RAD
    assert "first plan" in a.message
    plan_a, plan_b = Plan.from_result(world, a).to_dict(), Plan.from_result(world, b).to_dict()
    plan_a["stats"].pop("time_s")
    plan_b["stats"].pop("time_s")
    assert plan_a == plan_b


def test_improvement_ends_on_the_goal_within_a_narrow_angle_tolerance() -> None:
    """regrasp2 seed 40 (goal angle tolerance 0.1 rad): every improved plan once ended 0.103 rad off the goal's
    angle and was dropped for the first plan (11.8 rad); the grid reference's plan travels 9.1 rad."""
    from clew_ros.worlds import generate

    world = generate("regrasp2", 40).world()
    result = _plan(world, 0, 0.5)
    assert result.success
    assert result.stats["joint_travel_rad"] < 0.8 * result.stats["first_joint_travel_rad"]
    assert validate_plan(world, Plan.from_result(world, result)) == []


@pytest.mark.parametrize(
    ("check", "said"), [("goal_reached", "off the goal"), ("_dense_clear", "collides at the validator's step")]
)
def test_a_better_plan_the_final_checks_refuse_gives_the_first_plan_and_says_why(monkeypatch, check, said) -> None:
    """Every step checks what it builds, so the final checks never refuse a plan unless something is wrong; if
    they do, the first plan comes back and its stats and message say what they found (it once happened
    unseen on a narrow goal angle: test_improvement_ends_on_the_goal_within_a_narrow_angle_tolerance)."""
    from clew_ros.planar.improve import final as improvement

    world = _world("figure1")
    first = _plan(world, 0, 0.0)
    kept = _plan(world, 0, 0.3)
    assert kept.stats["joint_travel_rad"] < first.stats["joint_travel_rad"]
    assert "improve_refused" not in kept.stats
    monkeypatch.setattr(improvement, check, lambda *args, **kwargs: False)
    refused = _plan(world, 0, 0.3)
    assert said in refused.stats["improve_refused"]
    assert "refused" in refused.message
    assert said in refused.message
    assert refused.stats["joint_travel_rad"] == first.stats["joint_travel_rad"]
    assert [np.asarray(s.waypoints).tolist() for s in refused.segments] == [
        np.asarray(s.waypoints).tolist() for s in first.segments
    ]


def test_improve_time_zero_gives_exactly_the_first_plan() -> None:
    world = _world("figure1")
    result = _plan(world, 1, 0.0)
    assert result.stats["joint_travel_rad"] == result.stats["first_joint_travel_rad"]
    assert result.stats["improve_work"] == 0
    assert result.message == f"plan found with {len(result.tree)} landmarks, {result.stats['transfers']} grasp(s)"
    settings = PlannerSettings(seed=1, improve_time=0.0)
    ctx = PlanningContext(PlanarSpace(world), settings, np.random.default_rng(0), Termination(10))
    same = improve(world, ctx, result.segments, result.final_object_pose, world.object.goal)
    assert same.segments is result.segments
    assert same.final_object_pose is result.final_object_pose


class _StopAtPoll(Termination):
    """A termination that reports ``outcome`` from its ``at``-th poll on: a stop in the middle of the work, at
    the same point on every run and under any load (no clock)."""

    def __init__(self, at: int, outcome: Outcome) -> None:
        super().__init__(None)
        self.at = at
        self.outcome = outcome
        self.polls = 0

    def reason(self) -> Outcome | None:
        self.polls += 1
        return self.outcome if self.polls >= self.at else None


#: The stop comes at this poll of the termination: figure1's improvements of seeds 0 and 2 ask it about 190
#: and 300 times before they end on their own, so the stop falls while they are at work.
STOP_AT_POLL = 50


def test_cancel_during_improvement_returns_the_best_plan_so_far() -> None:
    """A cancel during the improvement (budget 60 s) ends it there, with a plan never worse than the first."""
    world = _world("figure1")
    first = _plan(world, 2, 0.0)
    settings = PlannerSettings(seed=2, improve_time=60.0)
    rng = np.random.default_rng([2, IMPROVE_STREAM])
    termination = _StopAtPoll(STOP_AT_POLL, Outcome.CANCELED)
    ctx = PlanningContext(PlanarSpace(world), settings, rng, termination)
    better = improve(world, ctx, first.segments, first.final_object_pose, world.object.goal)
    assert better.stopped  # it ended at the stop, not at its 60 s budget nor on its own
    assert better.travel <= better.first_travel
    assert better.transfers <= better.first_transfers
    result = dataclasses.replace(first, segments=better.segments, final_object_pose=better.final_object_pose)
    assert validate_plan(world, Plan.from_result(world, result)) == []


def test_the_time_limit_stops_improvement_and_keeps_the_plan() -> None:
    """The run's deadline falls during the improvement (budget 60 s): it stops there with a valid plan."""
    world = _world("figure1")
    first = _plan(world, 0, 0.0)
    settings = PlannerSettings(seed=0, improve_time=60.0)
    termination = _StopAtPoll(STOP_AT_POLL, Outcome.TIME_LIMIT)
    ctx = PlanningContext(PlanarSpace(world), settings, np.random.default_rng([0, IMPROVE_STREAM]), termination)
    better = improve(world, ctx, first.segments, first.final_object_pose, world.object.goal)
    assert better.stopped
    assert better.travel <= better.first_travel
    result = dataclasses.replace(first, segments=better.segments, final_object_pose=better.final_object_pose)
    assert result.outcome is Outcome.SUCCEEDED
    assert validate_plan(world, Plan.from_result(world, result)) == []


# -- random worlds: the straight-move check and improvement of random Manhattan paths ----------------------


RANDOM = [(1, 2, 0.0), (2, 3, 0.04), (3, 4, 0.02), (4, 5, 0.03)]


@pytest.mark.parametrize(("seed", "joints", "width"), RANDOM, ids=[f"seed{c[0]}_{c[1]}joints" for c in RANDOM])
def test_a_cleared_straight_move_is_valid_at_a_fine_step(seed, joints, width) -> None:
    world, rng = random_box_world(seed, joints, width)
    grasp_rel = np.array([0.02, 0.0, 0.3])
    cleared = 0
    for trial in range(60):
        a, b = rng.uniform(-3.0, 3.0, (2, joints)) * rng.uniform(0.05, 1.0)
        transfer = trial % 2 == 1
        rest = world.object.initial
        if not straight_move_clear(
            world, a, b, object_pose=rest, grasp_rel=grasp_rel if transfer else None, min_margin=5e-4
        ):
            continue
        cleared += 1
        steps = int(np.ceil(np.max(np.abs(b - a)) / FINE_RAD))
        q = a + np.linspace(0.0, 1.0, steps + 1)[:, None] * (b - a)
        poses = compose(tip_poses(world.robot, q), grasp_rel) if transfer else rest
        assert is_valid(world, q, poses).all()
    assert cleared >= 5


@pytest.mark.parametrize(("seed", "joints", "width"), RANDOM, ids=[f"seed{c[0]}_{c[1]}joints" for c in RANDOM])
def test_routing_around_a_blocked_move_gives_valid_paths_between_its_ends(seed, joints, width) -> None:
    """``_Improver.connect`` (RRT-Connect, moves checked continuously): a path it returns joins the move's ends,
    is valid at a fine step (resting object or carried one), and is the same from the same generator."""
    world, rng = random_box_world(seed, joints, width)
    grasp_rel = np.array([0.02, 0.0, 0.3])
    rest = np.asarray(world.object.initial, dtype=float)
    settings = PlannerSettings(seed=seed, improve_time=5.0)
    routed = 0
    for trial in range(40):
        transfer = trial % 2 == 1
        q = rng.uniform(-2.5, 2.5, (64, joints))
        poses = compose(tip_poses(world.robot, q), grasp_rel) if transfer else rest
        q = q[is_valid(world, q, poses)]
        if len(q) < 2:
            continue
        a, b = q[0], q[1]
        piece = _Piece("transfer" if transfer else "transit", 0 if transfer else None, np.array([a, b]), rest, None)
        piece.grasp_rel = grasp_rel if transfer else None
        paths = []
        for _ in range(2):
            ctx = PlanningContext(PlanarSpace(world), settings, np.random.default_rng([seed, trial]), Termination(30))
            improver = _Improver(world, ctx, [piece], world.object.goal)
            if improver.clear(piece, a, b):
                break  # not blocked
            paths.append(improver.connect(piece, a, b))
        if not paths or paths[0] is None:
            continue
        assert paths[1] is not None
        assert np.array_equal(paths[0], paths[1])  # deterministic
        path = paths[0]
        assert np.array_equal(path[0], a)
        assert np.array_equal(path[-1], b)
        routed += 1
        for u, v in itertools.pairwise(path):
            steps = int(np.ceil(np.max(np.abs(v - u)) / FINE_RAD))
            fine = u + np.linspace(0.0, 1.0, steps + 1)[:, None] * (v - u)
            poses = compose(tip_poses(world.robot, fine), grasp_rel) if transfer else rest
            assert is_valid(world, fine, poses).all()
    assert routed >= 2


@pytest.mark.parametrize(("seed", "joints", "width"), RANDOM, ids=[f"seed{c[0]}_{c[1]}joints" for c in RANDOM])
def test_improving_random_manhattan_paths_never_makes_them_invalid_or_longer(seed, joints, width) -> None:
    world, rng = random_box_world(seed, joints, width)
    candidates = rng.uniform(-1.5, 1.5, (200, joints))
    q0 = candidates[is_valid(world, candidates, world.object.initial)][0]
    genes = rng.normal(0.0, 1.5, (1, 4, joints))
    transit = run_manhattan(world, q0[None], genes, margin_m=1e-3, object_poses=world.object.initial[None])
    path = transit.waypoints[0]
    grasp_rel = relative(tip_poses(world.robot, path[-1:])[0], world.object.initial)  # as replay carries it
    genes = rng.normal(0.0, 1.5, (1, 4, joints))
    carried = run_manhattan(world, path[-1:], genes, margin_m=1e-3, grasp_rel=grasp_rel[None]).waypoints[0]
    segments = [Segment("transit", None, list(path)), Segment("transfer", 0, list(carried))]
    final = compose(tip_poses(world.robot, carried[-1:]), grasp_rel)[0]
    # the plan starts where the arm is, and its grasp 0 is where the transit's tip ends (in the object frame)
    grasps = np.array(world.object.grasps)
    grasps[0] = relative(world.object.initial, tip_poses(world.robot, path[-1:])[0])[:2]
    world = dataclasses.replace(
        world,
        robot=dataclasses.replace(world.robot, initial=q0),
        object=dataclasses.replace(world.object, goal=final, grasps=grasps),
    )
    settings = PlannerSettings(seed=seed, improve_time=0.2)
    ctx = PlanningContext(PlanarSpace(world), settings, np.random.default_rng(seed), Termination(30))
    before = joint_travel(segments)
    better = improve(world, ctx, segments, final, final)
    assert better.travel <= before + 1e-9
    assert better.travel < 0.9 * before  # random Manhattan paths wander: a shortcut always helps here
    assert better.transfers == 1
    assert [s.kind for s in better.segments] == ["transit", "transfer"]
    assert np.array_equal(better.segments[0].waypoints[0], segments[0].waypoints[0])  # the start stays
    # grasp and goal configurations may be chosen anew (the rebuild), but the plan stays valid, and more
    improved = Plan(
        world.name,
        tuple(world.robot.joint_names),
        True,
        "",
        segments=tuple(PlanSegment(s.kind, s.grasp, np.array(s.waypoints)) for s in better.segments),
        final_object_pose=better.final_object_pose,
    )
    assert validate_plan(world, improved) == []
    for motion in replay(world, improved, FINE_RAD):
        assert is_valid(world, motion.configurations, motion.object_poses).all()


# -- rebuilding the manipulation (regrasp proposals) ---------------------------------------------------------

OPEN_WORLD = open_reach()


def _plan_of(world, segments, final=None) -> Plan:
    plan = Plan(
        world.name,
        tuple(world.robot.joint_names),
        True,
        "",
        segments=tuple(PlanSegment(s.kind, s.grasp, np.array(s.waypoints)) for s in segments),
        final_object_pose=final,
    )
    if final is None:  # where the replay leaves the object
        plan = dataclasses.replace(plan, final_object_pose=list(replay(world, plan, None))[-1].object_poses[-1])
    return plan


def _regrasped_in_place(world) -> tuple[list[Segment], np.ndarray, np.ndarray, np.ndarray]:
    """A valid plan in the open world that puts the object down halfway and takes it again where it is, with
    the same grasp and without moving, and wanders: its segments, and the start, grasp and goal configurations."""
    start = world.robot.initial
    point = world.object.initial[:2] + world.object.grasps[0]
    hold, _, _ = solve_point(world.robot, np.array([[-0.12, 1.43]]), point[None])  # the tip on the grasp
    hold = hold[0]
    grasp_rel = relative(tip_poses(world.robot, hold[None])[0], world.object.initial)
    end, _, _ = solve_point(world.robot, np.array([[0.66, 1.52]]), world.object.goal[:2], offsets=grasp_rel[None, :2])
    end = end[0]  # the object's origin on the goal
    halfway = 0.5 * (hold + end)
    up = hold[1] + 0.3  # a needless back-and-forth of the elbow
    segments = [
        Segment("transit", None, [start, np.array([start[0], hold[1]]), hold]),
        Segment("transfer", 0, [hold, np.array([hold[0], up]), np.array([halfway[0], up]), halfway]),
        Segment("transit", None, [halfway]),
        Segment("transfer", 0, [halfway, np.array([halfway[0], end[1]]), end]),
    ]
    return segments, start, hold, end


def test_a_needless_regrasp_is_dropped_and_the_plan_gets_shorter(monkeypatch) -> None:
    """A valid plan that puts the object down halfway, takes it again, and wanders: one transfer does. The
    rebuilding finds it (the pruning's joining of regrasps in place, which would too, is turned off here)."""
    from clew_ros.planar.improve import base as improving

    monkeypatch.setattr(improving, "joined_regrasps", lambda pieces, same_rad: pieces)
    world = world_from_parameters(OPEN_WORLD)
    segments, start, hold, end = _regrasped_in_place(world)
    first = _plan_of(world, segments)
    assert validate_plan(world, first) == []  # the premise: a valid plan, with a needless regrasp
    goal = np.asarray(first.final_object_pose)
    ctx = PlanningContext(
        PlanarSpace(world), PlannerSettings(seed=0, improve_time=0.3), np.random.default_rng(0), Termination(30)
    )
    better = improve(world, ctx, segments, goal, np.asarray(world.object.goal, dtype=float))
    assert better.first_transfers == 2
    assert better.transfers == 1
    assert better.travel < better.first_travel - 0.5
    assert better.travel <= joint_travel([np.array([start, hold, end])]) + 1e-6  # as short as straight moves
    improved = _plan_of(world, better.segments, better.final_object_pose)
    assert validate_plan(world, improved) == []
    for motion in replay(world, improved, FINE_RAD):
        assert is_valid(world, motion.configurations, motion.object_poses).all()


def test_a_transfer_put_down_and_taken_again_in_place_becomes_one_transfer() -> None:
    # the same grasp taken again where the arm stopped: the arm and the object move exactly as before
    world = world_from_parameters(OPEN_WORLD)
    segments, _, _, _ = _regrasped_in_place(world)
    pieces = _pieces(world, segments)
    joined = joined_regrasps(pieces, ImproveSettings().same_rad)
    assert [p.kind for p in joined] == ["transit", "transfer"]
    assert np.array_equal(joined[1].waypoints, np.vstack([pieces[1].waypoints, pieces[3].waypoints[1:]]))
    assert np.array_equal(joined[1].grasp_rel, pieces[1].grasp_rel)
    assert np.abs(joined[1].end_pose(world) - pieces[3].end_pose(world)).max() <= 1e-9
    assert joint_travel([p.waypoints for p in joined]) == pytest.approx(joint_travel([p.waypoints for p in pieces]))
    assert validate_plan(world, _plan_of(world, [p.segment() for p in joined])) == []
    # when not (the arm moves between them, another grasp, elsewhere): test/core/test_improve_prune.py


def _improver_on_first_plan(name: str, seed: int = 0):
    """World ``name``, an improver (0.4 s budget) of its first plan with ``seed``, and a function making another
    one from the same first plan."""
    from clew_ros.planar.improve import _pieces

    world = _world(name)
    first = _plan(world, seed, 0.0)
    goal = np.asarray(world.object.goal, dtype=float)
    ctx = PlanningContext(
        PlanarSpace(world), PlannerSettings(seed=seed, improve_time=0.4), np.random.default_rng(seed), Termination(30)
    )

    def fresh() -> _Improver:
        return _Improver(world, ctx, _pieces(world, first.segments), goal)

    return world, fresh(), fresh


def test_goal_shortcuts_end_the_last_transfer_on_the_goal_sooner_by_a_clear_straight_move() -> None:
    # the goal leaves the object's angle free (arm3_regrasp, arm5_regrasp) or the arm is redundant (arm7): the
    # last transfer may end in another configuration holding the object on the goal, reached from one of its
    # waypoints by a clear straight move
    from clew_ros.planar.search import goal_reached
    from clew_ros.worlds import generate

    changed = 0
    for world in (_world("arm3_regrasp"), _world("arm5_regrasp"), generate("arm7", 1).world()):
        goal = np.asarray(world.object.goal, dtype=float)
        for seed in range(2):
            first = _plan(world, seed, 0.0)
            ctx = PlanningContext(
                PlanarSpace(world),
                PlannerSettings(seed=seed, improve_time=0.4),
                np.random.default_rng(seed),
                Termination(30),
            )
            improver = _Improver(world, ctx, _pieces(world, first.segments), goal)
            before = [p.waypoints.copy() for p in improver.pieces]
            spent = improver.budget.spent
            moved = improver.goal_shortcuts()
            assert improver.budget.spent > spent  # its inverse kinematics and checks are charged
            after = improver.pieces
            assert len(after) == len(before)
            assert all(np.array_equal(p.waypoints, w) for p, w in zip(after[:-1], before[:-1], strict=True))
            last, old = after[-1], before[-1]
            assert moved == (not np.array_equal(last.waypoints, old))
            if not moved:
                continue
            changed += 1
            kept = len(last.waypoints) - 1  # the waypoints kept, then a new end on the goal
            assert np.array_equal(last.waypoints[:kept], old[:kept])
            assert joint_travel([last.waypoints]) < joint_travel([old]) - 1e-9
            # the shortest of the ends found from every waypoint whose move is clear (all of them checked here)
            held, ok, _ = goal_holds_near(
                world, np.broadcast_to(last.grasp_rel, (len(old) - 1, 3)), old[:-1], goal, margin_m=improver.min_margin
            )
            clear = ok & straight_moves_clear(
                world, old[:-1], held, grasp_rel=last.grasp_rel, min_margin=improver.min_margin
            )
            shortest = min(joint_travel([np.vstack([old[: i + 1], held[i]])]) for i in np.flatnonzero(clear))
            assert joint_travel([last.waypoints]) == pytest.approx(shortest, abs=1e-9)
            assert goal_reached(world, last.end_pose(world), goal)
            assert straight_move_clear(
                world,
                last.waypoints[-2],
                last.waypoints[-1],
                grasp_rel=last.grasp_rel,
                min_margin=improver.min_margin,
            )
            segments = [p.segment() for p in after]
            assert validate_plan(world, _plan_of(world, segments)) == []
    assert changed >= 3


def test_proposals_are_compared_with_their_last_transfer_ended_on_the_goal_sooner(monkeypatch) -> None:
    """A checked proposal's last transfer gets the goal shortcut before the proposal is compared with the plan
    (a routed move that is shorter but leaves no goal shortcut must not win over one that, shortcut, is
    shorter still): the piece compared, and the plan's end when it is taken, is the shortcut one."""
    from clew_ros.planar.search import goal_reached

    calls = []
    changed = 0
    # first plans whose first rebuilding pass checks proposals that the goal shortcut makes shorter, and others
    for name, seed in (("arm3_regrasp", 0), ("arm5_regrasp", 0), ("arm5_regrasp", 2), ("single_transfer", 1)):
        world, improver, _ = _improver_on_first_plan(name, seed)
        goal = np.asarray(world.object.goal, dtype=float)
        original = improver.goal_shortcut

        def recording(piece, original=original, world=world, goal=goal):
            before = piece.waypoints.copy()
            assert goal_reached(world, piece.end_pose(world), goal)  # a proposal's last transfer, on the goal
            moved = original(piece)
            calls.append((piece, before, moved))
            return moved

        monkeypatch.setattr(improver, "goal_shortcut", recording)
        improver.rebuild_pass()
        for piece, before, moved in calls:
            assert moved == (not np.array_equal(piece.waypoints, before))
            if moved:
                changed += 1
                assert joint_travel([piece.waypoints]) < joint_travel([before]) - 1e-9
                assert goal_reached(world, piece.end_pose(world), goal)
        last = improver.pieces[-1]
        shortcut = [piece for piece, _, moved in calls if moved and piece is last]
        if shortcut:  # a proposal taken: the plan ends as it was compared
            assert validate_plan(world, _plan_of(world, [p.segment() for p in improver.pieces])) == []
        calls.clear()
    assert changed >= 1


def test_goal_shortcuts_change_nothing_after_a_transit_or_once_stopped() -> None:
    world = _world("arm3_regrasp")
    goal = np.asarray(world.object.goal, dtype=float)
    first = _plan(world, 0, 0.0)
    for pieces, limit in ((_pieces(world, first.segments)[:-1], 30.0), (_pieces(world, first.segments), 0.0)):
        settings = PlannerSettings(seed=0, improve_time=0.4)
        ctx = PlanningContext(PlanarSpace(world), settings, np.random.default_rng(0), Termination(limit))
        improver = _Improver(world, ctx, pieces, goal)  # ends with a transit; or its time limit is past
        before = [p.waypoints.copy() for p in improver.pieces]
        assert not improver.goal_shortcuts()
        assert improver.budget.spent == 0
        assert all(np.array_equal(p.waypoints, w) for p, w in zip(improver.pieces, before, strict=True))


def test_proposals_that_looked_clear_are_checked_without_routing_and_blocked_ones_apart(monkeypatch) -> None:
    # routing (RRT-Connect) is dear: a call for the proposals that looked clear never routes, and a call for
    # the blocked ones checks nothing else
    from clew_ros.planar.regrasp import propose

    world, improver, fresh_improver = _improver_on_first_plan("figure1")
    goal = np.asarray(world.object.goal, dtype=float)
    proposals, _ = propose(world, world.robot.initial, world.object.initial, goal, np.random.default_rng(2))
    clear = [p for p in proposals if p.blocked == 0]
    assert clear
    assert len(clear) < len(proposals)  # the premise: some looked blocked

    def no_routing(*_args, **_kwargs):
        raise AssertionError("routed a proposal")

    def recording(improver: _Improver, checked: list) -> None:
        original = improver.checked_tail

        def checked_tail(proposal, placement, slack):
            checked.append(proposal)
            return original(proposal, placement, slack)

        monkeypatch.setattr(improver, "checked_tail", checked_tail)

    placement = np.asarray(world.object.initial, float)
    checked: list = []
    recording(improver, checked)
    monkeypatch.setattr(improver, "connect", no_routing)
    travel = joint_travel([p.waypoints for p in improver.pieces])
    assert improver.try_proposals(proposals, 0, placement, routed=False)
    assert joint_travel([p.waypoints for p in improver.pieces]) < travel
    assert checked
    assert all(p.blocked == 0 for p in checked)
    # the blocked ones, from the first plan again: only they are checked
    fresh = fresh_improver()
    routed: list = []
    recording(fresh, routed)
    fresh.try_proposals(proposals, 0, placement, routed=True)
    assert routed
    assert all(p.blocked > 0 for p in routed)


def test_blocked_proposals_are_routed_fewer_transfers_first(monkeypatch) -> None:
    # a plan with fewer transfers always wins, so a blocked one-transfer proposal is routed before any
    # blocked two-transfer one, however long
    from clew_ros.planar.improve import rebuild as improve_module

    original = improve_module.propose

    def both_kinds(*args, **kwargs):
        return original(*args, **{**kwargs, "one_transfer": True, "two_transfers": True})

    monkeypatch.setattr(improve_module, "propose", both_kinds)  # each call makes both kinds
    lists: list = []
    for name in ("single_transfer", "arm3_regrasp", "figure1"):  # worlds until one shows the premise below
        _, improver, _ = _improver_on_first_plan(name)

        def try_proposals(proposals, kept, placement, *, routed):
            if routed:
                lists.append(list(proposals))
            return False

        monkeypatch.setattr(improver, "try_proposals", try_proposals)
        improver.rebuild_pass()
        mixed = [proposals for proposals in lists if len({len(p.grasps) for p in proposals}) > 1]
        if any(sorted(proposals, key=lambda p: p.rank) != proposals for proposals in mixed):
            break
    # the premise: a routing list holds both kinds, in an order that ranking by travel alone would change
    assert any(sorted(proposals, key=lambda p: p.rank) != proposals for proposals in mixed)
    for proposals in lists:
        keys = [(len(p.grasps), p.rank) for p in proposals]
        assert keys == sorted(keys)


def _shortcuts_in_numpy(w: np.ndarray, draws: np.ndarray, pieces: int):
    """The shortcuts as first written in numpy (session 17), from the same draws: the compiled kernel's
    reference (kernel.shortcuts)."""
    m, n = w.shape
    count = len(draws)
    cumulative = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(w, axis=0)).sum(axis=1))])
    kind = draws[:, 0]
    u = cumulative[-1] * np.sort(draws[:, 1:3], axis=1)
    one = np.minimum((draws[:, 3] * m).astype(int), m - 1)
    other = np.minimum((draws[:, 4] * (m - 1)).astype(int), m - 2)
    other += other >= one
    joint = np.minimum((draws[:, 5] * n).astype(int), n - 1)
    pick = kind < 1.0 / 3.0
    i, j = np.minimum(one, other), np.maximum(one, other)
    u[pick] = cumulative[np.stack([i, j], axis=1)[pick]]
    piece = np.clip(np.searchsorted(cumulative, u, side="right") - 1, 0, m - 2)
    piece[pick] = np.stack([i, j - 1], axis=1)[pick]
    span = cumulative[piece + 1] - cumulative[piece]
    share = np.where(span > 0, (u - cumulative[piece]) / np.where(span > 0, span, 1.0), 0.0)
    points = np.where((share == 0.0)[..., None], w[piece], w[piece] + share[..., None] * (w[piece + 1] - w[piece]))
    points[pick] = w[np.stack([i, j], axis=1)[pick]]
    a, b = points[:, 0], points[:, 1]
    first, last = piece[:, 0], piece[:, 1]
    inner = np.minimum(first[:, None] + 1 + np.arange(pieces), last[:, None])
    partial = kind >= 2.0 / 3.0
    paths = np.concatenate([a[:, None], np.repeat(b[:, None], pieces + 1, axis=1)], axis=1)
    along = np.concatenate([u[:, :1], cumulative[inner], u[:, 1:]], axis=1)
    bent = np.concatenate([a[:, None], w[inner], b[:, None]], axis=1)
    rows = np.arange(count)
    stretch = np.maximum(u[:, 1] - u[:, 0], 1e-300)
    bent[rows, :, joint] = (
        a[rows, joint][:, None] + (along - u[:, :1]) / stretch[:, None] * (b - a)[rows, joint][:, None]
    )
    paths[partial] = bent[partial]
    gain = (u[:, 1] - u[:, 0]) - np.abs(np.diff(paths, axis=1)).sum(axis=(1, 2))
    replaces = (last > first) & ~(partial & (last - first > pieces))
    fewer = replaces & (pick | (~partial & (last - first > 2)))
    return first, last, paths, np.where(replaces, gain, -np.inf), fewer


@pytest.mark.parametrize("joints", [2, 3, 7])
def test_the_compiled_shortcuts_are_the_numpy_ones(joints: int) -> None:
    from clew_ros.planar.kernel import shortcuts

    rng = np.random.default_rng(10 + joints)
    compared = 0
    for _ in range(40):
        w = pruned_path(random_path(rng, joints))
        if len(w) < 2:
            continue
        draws = rng.random((32, 6))
        draws[:4, 1:3] = [[0.0, 1.0], [0.0, 0.0], [1.0, 1.0], [0.5, 0.5]]  # the path's ends, one point twice
        got, want = shortcuts(w, draws, 8), _shortcuts_in_numpy(w, draws, 8)
        for name, g, e in zip(("first", "last", "paths", "gain", "fewer"), got, want, strict=True):
            if name in ("paths", "gain"):
                finite = np.isfinite(want[3])
                assert np.allclose(g[finite], e[finite], rtol=0.0, atol=1e-12), name
                assert np.array_equal(np.isfinite(got[3]), finite)
            else:
                assert np.array_equal(g, e), name
        compared += int(np.isfinite(want[3]).sum())
    assert compared > 300


def _on_piece(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float | None:
    """Where ``point`` lies on the straight piece ``a -> b`` (0..1), or ``None`` if it does not."""
    span = b - a
    t = float(span @ (point - a) / (span @ span)) if span @ span > 0 else 0.0
    close = np.allclose(a + t * span, point, atol=1e-9)
    return t if close and -1e-9 <= t <= 1 + 1e-9 else None


@pytest.mark.parametrize("joints", [2, 3, 7])
def test_drawn_shortcuts_join_two_points_of_the_path_and_save_what_they_say(joints: int) -> None:
    from clew_ros.planar.improve import _draw_shortcuts

    partial_pieces = ImproveSettings().partial_pieces

    rng = np.random.default_rng(joints)
    kinds = {"waypoints": 0, "straight": 0, "partial": 0}
    for _ in range(30):
        w = pruned_path(random_path(rng, joints))
        if len(w) < 3:
            continue
        cumulative = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(w, axis=0)).sum(axis=1))])
        drawn = _draw_shortcuts(w, rng, 16, partial_pieces)
        for k in range(16):
            first, last, path = int(drawn.first[k]), int(drawn.last[k]), drawn.paths[k]
            if not np.isfinite(drawn.gain[k]):
                assert last <= first or last - first > partial_pieces
                continue
            assert first < last
            start, end = path[0], path[-1]
            assert _on_piece(start, w[first], w[first + 1]) is not None
            assert _on_piece(end, w[last], w[last + 1]) is not None
            along = (cumulative[last] + np.abs(end - w[last]).sum()) - (
                cumulative[first] + np.abs(start - w[first]).sum()
            )
            assert drawn.gain[k] == pytest.approx(along - np.abs(np.diff(path, axis=0)).sum(), abs=1e-9)
            straight = np.allclose(path[1:], end, atol=0.0)
            if not straight:  # partial: the path's own waypoints in between, one joint evened out
                kinds["partial"] += 1
                inner = path[1 : 1 + last - first]
                assert np.allclose(path[last - first : -1], path[last - first])  # padded: zero moves
                differs = np.any(~np.isclose(inner, w[first + 1 : last + 1], atol=1e-12), axis=0)
                assert differs.sum() <= 1
                assert not drawn.fewer[k]  # as many waypoints as it replaces
            elif np.array_equal(start, w[first]) and np.array_equal(end, w[last + 1]):
                kinds["waypoints"] += 1  # two waypoints joined: the ones between are dropped
                assert drawn.fewer[k]
            else:
                kinds["straight"] += 1  # two points for the waypoints between: fewer only if three or more
                assert drawn.fewer[k] == (last - first > 2)
    assert min(kinds.values()) >= 20, kinds  # every kind is drawn


def test_a_batch_of_shortcuts_takes_the_clear_ones_that_do_not_overlap_largest_gain_first(monkeypatch) -> None:
    from clew_ros.planar.improve import _draw_shortcuts
    from clew_ros.planar.improve import base as improve_module

    tuning = ImproveSettings()

    _, improver, _ = _improver_on_first_plan("figure1")
    index = int(np.argmax([len(p.waypoints) for p in improver.pieces]))
    before = improver.pieces[index].waypoints.copy()
    drawn = _draw_shortcuts(before, np.random.default_rng(5), 64, tuning.partial_pieces)
    rows = drawn.improving(tuning.travel_eps)
    assert len(rows) >= 3  # a first plan's Manhattan path: many shortcuts would shorten it
    gains = drawn.gain[rows]
    assert np.all(np.diff(gains) <= 0)  # the largest gain first
    blocked = drawn.paths[rows[0]]  # the best one is blocked: every move of it comes back not clear
    calls = []

    def check(world, starts, ends, **kwargs):
        calls.append(len(starts))
        hit = [
            any(np.allclose(s, u) and np.allclose(e, v) for u, v in itertools.pairwise(blocked))
            for s, e in zip(starts, ends, strict=True)
        ]
        return ~np.array(hit, dtype=bool)

    monkeypatch.setattr(improve_module, "straight_moves_clear", check)
    assert improver.take_shortcuts(improver.pieces[index], drawn)
    assert len(calls) == 1  # the whole batch in one call
    taken = []
    for k in rows[1:]:  # what should be taken: the others, largest gain first, none overlapping one taken
        if all(drawn.last[k] < drawn.first[t] or drawn.first[k] > drawn.last[t] for t in taken):
            taken.append(k)
    after = improver.pieces[index].waypoints
    assert np.array_equal(after[0], before[0])
    assert np.array_equal(after[-1], before[-1])
    assert joint_travel([after]) <= joint_travel([before]) - drawn.gain[taken].sum() + 1e-9
    assert improver.shortcuts == len(taken)
    for k in taken:  # every shortcut taken is in the new path: its ends are waypoints of it
        for point in (drawn.paths[k][0], drawn.paths[k][-1]):
            assert np.min(np.max(np.abs(after - point), axis=1)) <= 1e-12 or _on_any_piece(after, point)

    monkeypatch.setattr(
        improve_module, "straight_moves_clear", lambda world, starts, ends, **kw: np.zeros(len(starts), bool)
    )
    again = improver.pieces[index].waypoints.copy()
    assert not improver.take_shortcuts(
        improver.pieces[index], _draw_shortcuts(again, np.random.default_rng(6), 16, tuning.partial_pieces)
    )
    assert np.array_equal(improver.pieces[index].waypoints, again)  # nothing clear: nothing changes


def _on_any_piece(path: np.ndarray, point: np.ndarray) -> bool:
    return any(_on_piece(point, a, b) is not None for a, b in itertools.pairwise(path))


def _with_and_without(seed: int, monkeypatch, *steps: str):
    """obstacles_32 (benchmarks) planned with ``seed``: the world, the plan, and the plan with the improver's
    ``steps`` turned off (the same first plan)."""
    from benchmarks.worlds import obstacles_world

    parameters = obstacles_world(32).parameters
    world = world_from_parameters(parameters)
    settings = PlannerSettings.from_parameters(parameters, seed=seed, time_limit=120)
    result = plan(world, settings)
    for step in steps:
        monkeypatch.setattr(_Improver, step, lambda self: False)
    without = plan(world, settings)
    assert result.success, result.message
    assert without.success, without.message
    assert without.stats["first_joint_travel_rad"] == result.stats["first_joint_travel_rad"]
    return world, result, without


def _never_worse(result) -> None:
    """The improved plan is never worse than the first one: no more transfers, no more joint travel."""
    assert result.stats["transfers"] <= result.stats["first_transfers"], result.stats
    assert result.stats["joint_travel_rad"] <= result.stats["first_joint_travel_rad"] + 1e-9, result.stats


def _quality(result) -> tuple[int, float]:
    """What the improvement lowers, in its order: transfers first, then joint travel (rad)."""
    return result.stats["transfers"], result.stats["joint_travel_rad"]


def test_on_a_three_joint_arm_one_regrasp_placed_on_the_lattice_takes_out_transfers_in_clutter(monkeypatch) -> None:
    # obstacles_32, seed 0: the first plan puts the object down more than once; every straight-move proposal
    # from its placements looks blocked, and a regrasp between its first and last grasps, put where the lattice
    # finds the way shortest, carries it in fewer transfers
    world, result, without = _with_and_without(0, monkeypatch, "lattice_regrasps", "lattice_first_grasps")
    assert validate_plan(world, Plan.from_result(world, result), step_rad=FINE_RAD) == []
    _never_worse(result)
    _never_worse(without)
    assert result.stats["transfers"] < result.stats["first_transfers"]  # the lattice's regrasp takes some out
    assert _quality(result) < _quality(without)


def test_on_a_three_joint_arm_the_transit_to_the_first_grasp_is_routed_again_on_the_lattice(monkeypatch) -> None:
    # obstacles_32, seed 4: the first plan's transit from the start to its first grasp goes a long way round among
    # the boxes (10 rad, twice its ends' joint travel); the lattice's shortest way there is shorter, to the same grasp
    world, result, without = _with_and_without(4, monkeypatch, "first_transit")
    assert validate_plan(world, Plan.from_result(world, result), step_rad=FINE_RAD) == []
    _never_worse(result)
    transit, before = np.asarray(result.segments[0].waypoints), np.asarray(without.segments[0].waypoints)
    assert np.array_equal(transit[0], before[0])
    assert np.array_equal(transit[-1], before[-1])  # the same first grasp
    assert joint_travel([transit]) < joint_travel([before]) - 1.0
    assert result.stats["joint_travel_rad"] < without.stats["joint_travel_rad"]


def test_on_a_three_joint_arm_another_first_grasp_found_on_the_lattice_shortens_the_plan(monkeypatch) -> None:
    # obstacles_32, seed 6: once the lattice's regrasp has taken the plan down to 2 transfers, it keeps its first
    # grasp configuration; taking the object another way (another approach, the transit routed on the lattice)
    # and placing the regrasp again shortens the plan
    world, result, without = _with_and_without(6, monkeypatch, "lattice_first_grasps")
    assert validate_plan(world, Plan.from_result(world, result), step_rad=FINE_RAD) == []
    _never_worse(result)
    assert result.stats["transfers"] <= without.stats["transfers"]
    assert result.stats["joint_travel_rad"] < without.stats["joint_travel_rad"]
    start = np.asarray(result.segments[0].waypoints[0])
    assert np.array_equal(start, without.segments[0].waypoints[0])  # from the same start
    taken, before = np.asarray(result.segments[1].waypoints[0]), np.asarray(without.segments[1].waypoints[0])
    assert np.abs(taken - before).max() > 0.1  # the object taken with another configuration
    grasp = result.segments[1].grasp
    point = compose(np.asarray(world.object.initial), np.r_[world.object.grasps[grasp], 0.0])[:2]
    assert np.linalg.norm(tip_poses(world.robot, taken[None])[0, :2] - point) < 1e-9  # at the grasp it names
