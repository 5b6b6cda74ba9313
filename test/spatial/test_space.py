"""clew_ros.spatial.space: the Ariadne's Clew planner on spatial worlds (motion-only and pick-and-place),
every plan checked at the validator's 0.002 rad under the checker of its mode."""

from __future__ import annotations

import copy
import itertools
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from clew_ros.core.manhattan import bounce
from clew_ros.core.settings import Outcome, PlannerSettings, Termination
from clew_ros.core.space import Mode
from clew_ros.core.tree import LandmarkTree
from clew_ros.spatial.distances import at_goal
from clew_ros.spatial.motion_plan import _MotionRun
from clew_ros.spatial.settle import rests, settle
from clew_ros.spatial.space import SpatialSpace, matrices, plan
from clew_ros.spatial.spheres import SphereSettings
from clew_ros.spatial.validate import ValidationSettings, validate_transit, validation_samples
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters

from .conftest import CONFIG

#: a coarse sphere model (conservative, builds fast): these tests are about planning on it
COARSE = SphereSettings(cell_m=0.03, protrusion_m=0.06)

ROBOT: dict[str, Any] = {
    "urdf": str(CONFIG / "robots/panda/panda.urdf"),
    "srdf": str(CONFIG / "robots/panda/panda.srdf"),
    "base_link": "panda_link0",
    "tip_link": "panda_hand_tcp",
    "gripper_links": ["panda_hand", "panda_leftfinger", "panda_rightfinger"],
}
BOUNDS = [-1.2, -1.2, -0.2, 1.2, 1.2, 1.6]

#: a motion-only query: swing from one side of a post on a table to the other, under a shelf
BOXES: dict[str, Any] = {
    "world": {
        "kind": "spatial",
        "name": "boxes",
        "bounds": BOUNDS,
        "robot": {
            **ROBOT,
            "initial": [0.8, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8],
            "goal": [-0.8, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8],
        },
        "obstacle_names": ["table", "post", "shelf"],
        "obstacles": {
            "table": {"shape": "box", "size": [0.6, 1.2, 0.04], "pose": [0.55, 0.0, 0.1, 0, 0, 0]},
            "post": {"shape": "box", "size": [0.08, 0.08, 0.9], "pose": [0.5, 0.0, 0.55, 0, 0, 0]},
            "shelf": {"shape": "box", "size": [0.4, 0.4, 0.04], "pose": [0.0, 0.6, 0.9, 0, 0, 0]},
        },
    }
}

#: pick a box up on a table and put it down 0.6 m away: one transfer, top-down grasps
TABLE: dict[str, Any] = {
    "world": {
        "kind": "spatial",
        "name": "table",
        "bounds": BOUNDS,
        "robot": {**ROBOT, "initial": [0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8]},
        "obstacle_names": ["table"],
        "obstacles": {"table": {"shape": "box", "size": [0.6, 1.2, 0.04], "pose": [0.55, 0.0, 0.1, 0, 0, 0]}},
        "supports": ["table"],
        "object": {
            "shape": "box",
            "size": [0.04, 0.04, 0.12],
            "initial": [0.5, 0.3, 0.18, 0, 0, 0.3],
            "goal": [0.5, -0.3, 0.18, 0, 0, 0],
            "grasps": [0, 0, 0.02, math.pi, 0, 0, 0, 0, 0.02, math.pi, 0, math.pi / 2],
        },
    }
}

SETTINGS = PlannerSettings(seed=1, time_limit=60.0)


@pytest.fixture(scope="module")
def boxes(tmp_path_factory: pytest.TempPathFactory) -> SpatialWorld:
    return spatial_world_from_parameters(BOXES, Path(tmp_path_factory.mktemp("w")), COARSE)


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> SpatialWorld:
    # the default model: the coarse one's fingers reach into the table under a top-down grasp
    return spatial_world_from_parameters(TABLE, Path(tmp_path_factory.mktemp("w")))


def transfer_problems(space: SpatialSpace, grasp: int, waypoints: np.ndarray) -> list[int]:
    """Pieces of a transfer with an invalid configuration at the validator's steps (the object held)."""
    checker = space.transfer_checker(space.grasp_rel(grasp))
    steps = np.full(space.dof, ValidationSettings().step_rad)
    return [
        i
        for i in range(len(waypoints) - 1)
        if not checker.valid(validation_samples(waypoints[i], waypoints[i + 1], steps)).all()
    ]


def check_plan(world: SpatialWorld, segments: list[Any], final: np.ndarray) -> None:
    """Every piece valid in its mode; a transfer starts holding its grasp and ends at a stable placement."""
    space = SpatialSpace(world)
    assert world.object is not None
    resting = np.array(world.object.initial)
    assert np.allclose(segments[0].waypoints[0], world.initial, atol=1e-9)
    for before, after in itertools.pairwise(segments):
        assert np.allclose(before.waypoints[-1], after.waypoints[0], atol=1e-6)
    for segment in segments:
        path = np.array(segment.waypoints)
        if segment.kind == "transit":
            assert validate_transit(space.transit_checker(resting), path) == []
            continue
        tcp = space.tcp(path[:1])[0]
        held_at = matrices(resting)[0] @ matrices(world.object.grasps[segment.grasp])[0]
        assert np.allclose(tcp, held_at, atol=1e-4)  # it holds the grasp where the object rests
        assert transfer_problems(space, segment.grasp, path) == []
        resting = space.held_object_poses(path[-1:], space.grasp_rel(segment.grasp))[0]
        assert rests(space.world, resting)
    assert np.allclose(resting, final, atol=1e-4)
    assert at_goal(space.parts, final, np.array(world.object.goal))


def test_a_motion_among_boxes_is_valid_at_the_validators_step(boxes: SpatialWorld) -> None:
    result = plan(boxes, SETTINGS)
    assert result.outcome is Outcome.SUCCEEDED, result.message
    assert [s.kind for s in result.segments] == ["transit"]
    path = np.array(result.segments[0].waypoints)
    assert np.array_equal(path[0], boxes.initial)
    assert boxes.goal is not None
    assert np.max(np.abs(path[-1] - boxes.goal)) <= 1e-6
    assert validate_transit(boxes.checker, path) == []
    assert result.final_object_pose is None
    # the straight move is blocked (the post): the planner went round it, and its shortcuts never lengthen
    assert validate_transit(boxes.checker, np.array([boxes.initial, boxes.goal])) != []
    assert result.stats["joint_travel_rad"] <= result.stats["first_joint_travel_rad"]


def test_same_seed_same_motion(boxes: SpatialWorld) -> None:
    first, again = plan(boxes, SETTINGS), plan(boxes, SETTINGS)
    assert first.outcome is Outcome.SUCCEEDED, first.message
    assert np.array_equal(np.array(first.segments[0].waypoints), np.array(again.segments[0].waypoints))
    assert first.stats["goal_landmarks"] == again.stats["goal_landmarks"] >= 1


def test_a_motion_joined_at_a_goal_tree_landmark_runs_from_start_to_goal(boxes: SpatialWorld) -> None:
    """The path through a landmark of the goal's tree: the start's branch, SEARCH's path, then the goal
    tree's branch walked back to the goal (each landmark's path runs from its parent, the goal's side)."""
    assert boxes.goal is not None
    space = SpatialSpace(boxes)
    run = _MotionRun(space, PlannerSettings(seed=0, time_limit=30.0, improve_time=0.0), Termination(30.0))
    none = np.zeros(6)
    run.goal_tree = LandmarkTree(boxes.goal, none)
    rng = np.random.default_rng(0)
    ends = {}
    for tree, root, name in ((run.tree, boxes.initial, "start"), (run.goal_tree, boxes.goal, "goal")):
        decoded = space.manhattan(
            root[None], rng.normal(0.0, 0.5, size=(1, 1, 7)), Mode.resting(none[None]), margin_m=1e-3,
            counters=None, should_stop=None, threads=1,
        )  # fmt: skip
        way = decoded.waypoints[0]
        tree.add(parent=0, joints=way[-1], object_pose=none, grasp=None, grasp_rel=None, transit=way, transfer=None)
        ends[name] = way
    between = np.linspace(ends["start"][-1], ends["goal"][-1], 5)
    result = run.success(1, between, 1, boxes.goal)
    path = np.array(result.segments[0].waypoints)
    assert np.array_equal(path[0], boxes.initial)
    assert np.array_equal(path[-1], boxes.goal)
    expected = np.vstack([ends["start"], between[1:], ends["goal"][::-1][1:]])
    assert np.allclose(path, expected)
    assert result.stats["joint_travel_rad"] == pytest.approx(np.abs(np.diff(expected, axis=0)).sum(), abs=1e-5)


def test_a_failed_search_that_got_nearer_the_other_tree_leaves_a_landmark(boxes: SpatialWorld) -> None:
    assert boxes.goal is not None
    run = _MotionRun(SpatialSpace(boxes), PlannerSettings(seed=0), Termination(30.0))
    others = boxes.goal[None]
    toward = np.linspace(boxes.initial, boxes.goal, 4)[:2]  # a third of the way: nearer by far more than 0.1 rad
    run.keep_end(run.tree, run.tree[0], toward, others)
    assert len(run.tree) == 2
    kept = run.tree[1]
    assert kept.parent == 0
    assert np.array_equal(kept.joints, toward[-1])
    assert kept.transit is not None
    assert np.array_equal(kept.transit, toward)
    away = np.array([boxes.initial, boxes.initial + (boxes.initial - boxes.goal) * 0.1])
    run.keep_end(run.tree, run.tree[0], away, others)  # farther: no landmark
    assert len(run.tree) == 2


def test_a_pick_and_place_on_a_table(table: SpatialWorld) -> None:
    result = plan(table, SETTINGS)
    assert result.outcome is Outcome.SUCCEEDED, result.message
    kinds = [s.kind for s in result.segments]
    assert kinds[:2] == ["transit", "transfer"]
    assert result.stats["transfers"] >= 1
    assert result.final_object_pose is not None
    check_plan(table, result.segments, result.final_object_pose)
    # every landmark's object rests on a support (EXPLORE's transfers end at stable placements)
    space = SpatialSpace(table)
    assert all(rests(space.world, landmark.object_pose) for landmark in result.tree)


def test_same_seed_same_plan(table: SpatialWorld) -> None:
    settings = PlannerSettings(seed=3, time_limit=60.0)
    first, second = plan(table, settings), plan(table, settings)
    assert first.outcome is Outcome.SUCCEEDED, first.message
    assert second.outcome is first.outcome
    assert len(first.segments) == len(second.segments)
    for a, b in zip(first.segments, second.segments, strict=True):
        assert (a.kind, a.grasp) == (b.kind, b.grasp)
        assert np.array_equal(np.array(a.waypoints), np.array(b.waypoints))
    assert first.final_object_pose is not None
    assert second.final_object_pose is not None
    assert np.array_equal(first.final_object_pose, second.final_object_pose)


def test_the_improvement_joins_a_transfer_carried_back_and_forth_and_taken_again_in_place(table: SpatialWorld) -> None:
    """A valid plan of two transfers: the object carried to the goal, put down, taken again by the same grasp
    without the arm moving, carried back to the start and to the goal again. The pruning (no checking: a loop,
    then a regrasp in place) makes it a plan of one transfer before the shortcuts, valid at the validator's
    step."""
    from clew_ros.core.settings import Termination
    from clew_ros.core.space import PlanningContext
    from clew_ros.core.tree import Segment
    from clew_ros.spatial.improvement import shortcut_segments
    from clew_ros.spatial.plan import make_plan, path_problems

    found = plan(table, PlannerSettings(seed=0, time_limit=60.0, improve_time=0.0))
    assert found.outcome is Outcome.SUCCEEDED, found.message
    assert found.final_object_pose is not None
    carried = found.segments[-1]
    assert carried.kind == "transfer"
    there = np.array(carried.waypoints)
    segments = [
        *found.segments,
        Segment("transit", None, [there[-1]]),
        Segment("transfer", carried.grasp, [*there[::-1], *there[1:]]),
    ]
    built = [(s.kind, s.grasp, np.asarray(s.waypoints, dtype=float)) for s in segments]
    assert path_problems(table, make_plan(table, built)) == []  # the premise: a valid plan
    space = SpatialSpace(table)
    ctx = PlanningContext(space, PlannerSettings(seed=0, improve_time=0.5), np.random.default_rng(0), Termination(60))
    better = shortcut_segments(space.parts, ctx, segments, found.final_object_pose)
    assert (better.first_transfers, better.transfers) == (found.stats["transfers"] + 1, found.stats["transfers"])
    assert better.travel <= found.stats["joint_travel_rad"] + 1e-9 < better.first_travel
    check_plan(table, better.segments, found.final_object_pose)
    built = [(s.kind, s.grasp, np.asarray(s.waypoints, dtype=float)) for s in better.segments]
    assert path_problems(table, make_plan(table, built)) == []


def test_a_goal_that_is_no_stable_placement_is_refused_at_once(table: SpatialWorld) -> None:
    floating = np.array([0.5, -0.3, 0.3, 0.0, 0.0, 0.0])  # 12 cm above the table
    result = plan(table, SETTINGS, goal=floating)
    assert result.outcome is Outcome.INVALID_WORLD
    assert "is not a stable placement" in result.message
    assert "table" in result.message
    assert len(result.tree) == 1
    assert result.stats["evaluations"] == 0
    tilted = np.array([0.5, -0.3, 0.18, 0.3, 0.0, 0.0])
    assert plan(table, SETTINGS, goal=tilted).outcome is Outcome.INVALID_WORLD


def test_a_goal_in_collision_or_out_of_reach_is_refused_at_once(tmp_path: Path) -> None:
    tree = copy.deepcopy(TABLE)
    tree["world"]["obstacle_names"] = ["table", "block"]
    tree["world"]["obstacles"]["block"] = {"shape": "box", "size": [0.1, 0.1, 0.1], "pose": [0.5, -0.3, 0.2, 0, 0, 0]}
    world = spatial_world_from_parameters(tree, tmp_path, COARSE)
    result = plan(world, SETTINGS)
    assert result.outcome is Outcome.GOAL_IN_COLLISION
    assert "block" in result.message
    far = copy.deepcopy(TABLE)
    far["world"]["obstacle_names"] = ["table", "far"]
    far["world"]["obstacles"]["far"] = {"shape": "box", "size": [0.6, 0.6, 0.04], "pose": [3.0, 0.0, 0.1, 0, 0, 0]}
    far["world"]["supports"] = ["table", "far"]
    far["world"]["bounds"] = [-1.2, -1.2, -0.2, 3.6, 1.2, 1.6]
    far["world"]["object"]["goal"] = [3.0, 0.0, 0.18, 0, 0, 0]
    result = plan(spatial_world_from_parameters(far, tmp_path, COARSE), SETTINGS)
    assert result.outcome is Outcome.GOAL_OUT_OF_REACH
    assert "out of reach" in result.message


def test_decoded_transfers_end_with_the_object_resting(table: SpatialWorld) -> None:
    space = SpatialSpace(table)
    assert table.object is not None
    initial = np.array(table.object.initial)
    rel = space.grasp_rel(0)
    target = matrices(initial)[0] @ matrices(table.object.grasps[0])[0]
    holds = space.ik(32).solve(target, np.random.default_rng(0), checker=space.transit_checker(initial))
    holds = holds[space.transfer_checker(rel).valid(holds)]
    assert len(holds) > 0
    start = holds[0]
    # lifted 8 cm: set down again on the table, by a clear straight move
    lifted_pose = space.tcp(start[None])[0]
    lifted_pose[2, 3] += 0.08
    lifted = space.ik(0).solve(lifted_pose, np.random.default_rng(0), seeds=start[None])
    assert len(lifted) > 0
    settled, ok = settle(space.parts, space.transfer_checker(rel), rel, lifted[:1])
    assert ok.tolist() == [True]
    assert rests(space.world, space.held_object_poses(settled, rel)[0])
    # random Manhattan transfers from the hold: every end rests (set down, or the path stays at its start)
    genes = np.random.default_rng(1).normal(0.0, 0.6, size=(12, 1, space.dof))
    paths = space.manhattan(
        np.repeat(start[None], 12, axis=0),
        genes,
        Mode.held(np.repeat(rel[None], 12, axis=0)),
        margin_m=0.0,
        counters=None,
        should_stop=None,
        threads=1,
    )
    assert all(rests(space.world, pose) for pose in paths.object_poses)
    checker = space.transfer_checker(rel)
    for path in paths.waypoints:
        assert checker.valid(path).all()


def test_motion_only_refusals(boxes: SpatialWorld) -> None:
    assert boxes.goal is not None
    colliding = np.array([0.0, 0.6, 0.0, -1.4, 0.0, 2.0, 0.8])
    assert not boxes.checker.valid(colliding[None])[0]
    result = plan(boxes, SETTINGS, goal=colliding)
    assert result.outcome is Outcome.GOAL_IN_COLLISION
    beyond = boxes.goal.copy()
    beyond[3] = 0.5  # joint 4's upper limit is -0.0698
    result = plan(boxes, SETTINGS, goal=beyond)
    assert result.outcome is Outcome.INVALID_WORLD
    assert "world.robot.goal" in result.message


def test_free_intervals_searched_only_as_far_as_asked(boxes: SpatialWorld) -> None:
    rng = np.random.default_rng(2)
    qs = rng.uniform(boxes.robot.lower, boxes.robot.upper, size=(400, boxes.robot.dof))
    qs = qs[boxes.checker.valid(qs)][:40]
    reach = rng.uniform(0.0, 1.5, size=len(qs))
    for joint in (0, 3):
        lo, hi, ok = boxes.checker.free_intervals(qs, joint)
        near_lo, near_hi, near_ok = boxes.checker.free_intervals(qs, joint, reach=reach)
        assert np.array_equal(ok, near_ok)
        # the same steps from the start, stopped at the reach: the whole interval clipped to it
        assert np.allclose(near_hi, np.minimum(hi, qs[:, joint] + reach), atol=1e-12)
        assert np.allclose(near_lo, np.maximum(lo, qs[:, joint] - reach), atol=1e-12)


def test_a_folded_move_bounces_as_over_the_whole_interval(boxes: SpatialWorld) -> None:
    """``move=``: the side the move heads for searched as far as it, the other only as far as its fold goes;
    the bounced value is the one over the whole interval, and the far side is searched no further than
    needed (often not at all)."""
    rng = np.random.default_rng(3)
    qs = rng.uniform(boxes.robot.lower, boxes.robot.upper, size=(600, boxes.robot.dof))
    qs = qs[boxes.checker.valid(qs)][:60]
    moves = rng.normal(0.0, 1.5, size=len(qs))
    moves[:5] = 0.0
    spared = 0
    for joint in range(boxes.robot.dof):
        lo, hi, ok = boxes.checker.free_intervals(qs, joint)
        f_lo, f_hi, f_ok = boxes.checker.free_intervals(qs, joint, move=moves)
        assert np.array_equal(ok, f_ok)
        start = qs[:, joint]
        whole = bounce(start + moves, lo, hi)
        folded = bounce(start + moves, f_lo, f_hi)
        assert np.allclose(np.where(ok, folded, start), np.where(ok, whole, start), atol=1e-9)
        far = np.where(moves >= 0.0, start - f_lo, f_hi - start)
        spared += int(np.sum(ok & (far == 0.0) & (np.where(moves >= 0.0, start - lo, hi - start) > 0.0)))
    assert spared > 0
    with pytest.raises(ValueError, match="reach or move"):
        boxes.checker.free_intervals(qs, 0, reach=1.0, move=moves)


def test_a_motion_stopped_by_its_time_limit_says_so(boxes: SpatialWorld) -> None:
    result = plan(boxes, PlannerSettings(seed=1, time_limit=0.01))
    assert result.outcome is Outcome.TIME_LIMIT
    assert result.message.startswith("time limit of 0.01 s reached after ")
    assert "landmarks; no motion found" in result.message
    assert result.segments == []


def test_an_improvement_the_validator_refuses_is_not_returned(monkeypatch: pytest.MonkeyPatch) -> None:
    """An improvement whose plan the validator's checks refuse (here: made to put a transit waypoint past a joint
    limit) is not returned: the run returns its first plan (valid), saying what was refused."""
    from dataclasses import replace as replaced

    from clew_ros.spatial import improvement
    from clew_ros.spatial.offline import checked_plan
    from clew_ros.worlds.spatial import generate_spatial

    world = generate_spatial("spatial_table", 0, "panda").world()
    improved = improvement.improved

    def faulty(*args: Any, **kwargs: Any) -> Any:
        better = improved(*args, **kwargs)
        first = better.segments[0]
        past = np.array(first.waypoints[0], dtype=float)
        past[0] = world.robot.upper[0] + 0.1
        broken = replaced(first, waypoints=[first.waypoints[0], past, *first.waypoints])
        return replaced(better, segments=[broken, *better.segments[1:]])

    monkeypatch.setattr(improvement, "improved", faulty)
    result = plan(world, PlannerSettings(seed=0, time_limit=30.0))
    assert result.outcome is Outcome.SUCCEEDED, result.message
    assert "outside its limits" in result.stats["improve_refused"]
    assert result.stats["joint_travel_rad"] == result.stats["first_joint_travel_rad"]
    assert checked_plan(world, result).code == "SUCCEEDED"
