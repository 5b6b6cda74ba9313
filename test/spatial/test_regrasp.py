"""Regrasping in 3-D (issue 53): generated worlds where a regrasp is necessary, SEARCH by way of intermediate
placements, transfers that lift the object off and set it down from above, and outcomes that never claim
more than was shown."""

from __future__ import annotations

import functools
import math
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("coal")

from clew_ros.core.explore import Exploration, Explorer
from clew_ros.core.plan import Plan
from clew_ros.core.settings import Outcome, PlannerSettings
from clew_ros.core.space import Mode, PlanningContext
from clew_ros.core.tree import Landmark, Segment
from clew_ros.spatial.handling import DragSettings, drag_problems, slides
from clew_ros.spatial.lift import drag_free, lifted_segments, slid_level
from clew_ros.spatial.placements import face_yaw, sample_placements
from clew_ros.spatial.plan import make_plan, replay, validate_plan
from clew_ros.spatial.settle import rests
from clew_ros.spatial.space import SpatialSpace, plan
from clew_ros.spatial.targets import goal_configurations
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.tuning import SpatialTuning
from clew_ros.spatial.turns import turnable
from clew_ros.spatial.ways import way_out
from clew_ros.spatial.world import SpatialWorld
from clew_ros.worlds.spatial import SpatialGenerated, generate_spatial
from clew_ros.worlds.spatial_regrasp import RejectedError, hand_blocked, single_grasp_refutation


@functools.cache
def generated(family: str, seed: int) -> SpatialGenerated:
    return generate_spatial(family, seed, "panda")


@pytest.mark.parametrize("family", ["spatial_bin_cubby", "spatial_cubby_bin", "spatial_shelf_bin", "spatial_bin_shelf"])
def test_a_regrasp_world_has_a_two_transfer_witness_and_no_single_grasp(family: str) -> None:
    made = generated(family, 0)
    world = made.world()
    assert made.witness.grasp_count == 2
    assert validate_plan(world, made.witness) == []  # on the exact geometry, at 0.002 rad
    assert drag_problems(world, made.witness) == []
    reasons = single_grasp_refutation(world)
    assert world.object is not None
    assert len(reasons) == len(world.object.grasps)  # every grasp refuted, at the start or at the goal
    used = {s.grasp for s in made.witness.segments if s.kind == "transfer"}
    assert len(used) == 2


def test_the_refutation_fails_when_an_enclosure_opens() -> None:
    world = generated("spatial_bin_cubby", 0).world()
    walls = ("cubby_ceiling", "cubby_back", "cubby_left", "cubby_right")
    opened = replace(world, obstacles=tuple(o for o in world.obstacles if o.name not in walls))
    with pytest.raises(RejectedError, match="blocked neither"):
        single_grasp_refutation(opened)  # a grasp from above now fits at the goal


def test_a_hand_in_a_bin_is_blocked_from_the_side_not_from_above() -> None:
    made = generated("spatial_bin_cubby", 0)
    world = made.world()
    assert world.object is not None
    start = pose_matrix(list(world.object.initial))
    blocked = [hand_blocked(world.robot, start @ pose_matrix(list(g)), world.obstacles) for g in world.object.grasps]
    assert all(blocked[2:])  # the side grasps (clew_ros.worlds.spatial_holds.grasps_of: two from above first)
    first = next(s.grasp for s in made.witness.segments if s.kind == "transfer")
    assert first is not None
    assert first < 2
    assert not blocked[first]


def test_the_planner_regrasps_where_no_single_transfer_exists() -> None:
    world = generated("spatial_bin_cubby", 0).world()
    result = plan(world, PlannerSettings(seed=0, time_limit=30.0))
    assert result.outcome is Outcome.SUCCEEDED, result.message
    built = make_plan(world, [(s.kind, s.grasp, s.waypoints) for s in result.segments])
    assert built.grasp_count >= 2
    assert validate_plan(world, built) == []
    again = plan(world, PlannerSettings(seed=0, time_limit=30.0))  # same seed, same plan
    assert [np.asarray(s.waypoints).tobytes() for s in again.segments] == [
        np.asarray(s.waypoints).tobytes() for s in result.segments
    ]


@pytest.mark.parametrize("proves", [True, False])
def test_the_resolution_criterion_is_no_proof_in_spatial_worlds(proves: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    """EXPLORE's every step lands on the landmark it started from, every pair searched (the paper's criterion
    met at once): the paper's rule answers NO_PATH_AT_RESOLUTION; the spatial planner's
    (``SearchSettings.resolution_proves`` off) goes on to its time limit and says what it tried."""
    world = generated("spatial_bin_cubby", 0).world()
    original = Explorer.explore

    def explore_in_place(self: Explorer) -> Exploration | None:
        found = original(self)
        if found is None:
            return None
        parent = self.tree[found.fields["parent"]]
        fields = {**found.fields, "joints": parent.joints.copy(), "object_pose": parent.object_pose.copy()}
        return Exploration(fields, 0.0, covered=True, moved=True)

    monkeypatch.setattr(Explorer, "explore", explore_in_place)
    search = replace(SpatialTuning().search, via_placements=0, search_from_start=False, resolution_proves=proves)
    result = plan(world, PlannerSettings(seed=0, time_limit=2.0, improve_time=0.0), tuning=SpatialTuning(search=search))
    if proves:
        assert result.outcome is Outcome.NO_PATH_AT_RESOLUTION, result.message
    else:
        assert result.outcome in {Outcome.TIME_LIMIT, Outcome.SUCCEEDED}, result.message
        assert result.outcome is Outcome.SUCCEEDED or "tried:" in result.message


def _sliding_plan(world: SpatialWorld, witness: Plan, shift_m: float) -> tuple[Plan, list[Segment]]:
    """The witness's first hold, then a transfer that slides the object ``shift_m`` over its table (towards the
    table's centre) and then lifts it 5 cm, each tcp position reached by inverse kinematics."""
    space = SpatialSpace(world)
    first = next(m for m in replay(world, witness) if m.kind == "transfer")
    q0 = first.configurations[0]
    tcp = space.tcp(q0[None])[0]
    towards = np.asarray(world.supports[0].center) - tcp[:2, 3]
    towards /= np.linalg.norm(towards)
    path = [q0]
    for move in [*(towards * f * shift_m for f in (0.25, 0.5, 0.75, 1.0)), None]:
        target = tcp.copy()
        target[:2, 3] += towards * shift_m if move is None else move
        target[2, 3] += 0.05 if move is None else 0.0
        found = space.ik(1).solve_many([target], np.random.default_rng(0), seeds=[path[-1][None]])[0]
        path.append(found[np.argmin(np.abs(found - path[-1]).sum(axis=1))])
    segments = [
        Segment("transit", None, list(witness.segments[0].waypoints)),
        Segment("transfer", first.grasp, path),
    ]
    built = make_plan(world, [(s.kind, s.grasp, s.waypoints) for s in segments])
    return built, segments


def test_dragging_is_found_and_a_lift_mends_it() -> None:
    made = generate_spatial("spatial_table", 0, "panda")
    world = made.world()
    dragging, segments = _sliding_plan(world, made.witness, 0.03)
    problems = drag_problems(world, dragging)
    assert problems
    assert "slides" in problems[0]
    assert drag_problems(world, dragging, DragSettings(slide_m=0.05)) == []  # 3 cm is within a 5 cm allowance
    space = SpatialSpace(world)
    path = np.asarray(segments[1].waypoints)
    rel = space.grasp_rel(segments[1].grasp)
    assert not drag_free(space, path[:1], path[4:5], rel)[0]  # the slide, as one straight move (a shortcut)
    assert drag_free(space, path[4:5], path[5:6], rel)[0]  # the lift after it
    mended = lifted_segments(space, segments)
    built = make_plan(world, [(s.kind, s.grasp, s.waypoints) for s in mended])
    assert len(mended[1].waypoints) != len(segments[1].waypoints)
    assert drag_problems(world, built) == []


def test_a_slide_in_the_middle_of_a_transfer_is_lifted_too() -> None:
    """The object lifted off, put back down on its table, slid 3 cm and lifted: the slide in the middle is
    replaced by the same move raised at both ends."""
    made = generate_spatial("spatial_table", 0, "panda")
    world = made.world()
    _, segments = _sliding_plan(world, made.witness, 0.03)
    space = SpatialSpace(world)
    path = np.asarray(segments[1].waypoints)
    target = space.tcp(path[:1])[0].copy()
    target[2, 3] += 0.03
    up = space.ik(1).solve_many([target], np.random.default_rng(0), seeds=[path[:1]])[0][0]
    segments[1] = Segment("transfer", segments[1].grasp, [path[0], up, *path])
    built = make_plan(world, [(s.kind, s.grasp, s.waypoints) for s in segments])
    assert drag_problems(world, built)
    mended = lifted_segments(space, segments)
    again = make_plan(world, [(s.kind, s.grasp, s.waypoints) for s in mended])
    assert drag_problems(world, again) == []
    assert np.array_equal(np.asarray(mended[1].waypoints[0]), path[0])  # it still starts where the object rests


@functools.cache
def ur5_cubby() -> SpatialWorld:
    """A UR5 world whose goal lies in a cubby turned so that, with the goal turned a quarter, the UR5's
    fingerless tool reaches it through a side wall: a goal configuration with no way in."""
    return generate_spatial("spatial_bin_cubby", 401, "ur5").world()


def _context(space: SpatialSpace, seed: int = 0) -> PlanningContext:
    return PlanningContext(space, PlannerSettings(seed=seed), np.random.default_rng(seed), search=space.tuning.search)


def test_joints_whose_limits_span_a_turn_come_the_short_way() -> None:
    world = ur5_cubby()
    space = SpatialSpace(world)
    robot = world.robot
    assert not robot.continuous.any()  # revolute, +-2 pi
    assert turnable(robot.prismatic, robot.lower, robot.upper).all()
    q0 = np.zeros(robot.dof)
    far = np.full(robot.dof, 5.5)
    near = space.nearest_turns(q0, far[None])[0]
    assert np.allclose(near, 5.5 - 2 * np.pi)  # the same posture, a turn nearer
    narrowed = replace(robot, lower=np.full(robot.dof, -1.0), upper=np.full(robot.dof, 5.0))  # 6 rad: less than a turn
    assert not turnable(narrowed.prismatic, narrowed.lower, narrowed.upper).any()


def test_goal_configurations_with_a_way_in_come_first() -> None:
    world = ur5_cubby()
    space = SpatialSpace(world)
    assert world.object is not None
    goal = np.asarray(world.object.goal, dtype=float)
    ctx = _context(space)
    witness = generate_spatial("spatial_bin_cubby", 401, "ur5").witness
    grasp = next(s.grasp for s in reversed(witness.segments) if s.kind == "transfer")
    assert grasp is not None
    rel = space.grasp_rel(grasp)
    checker = space.transfer_checker(rel)
    found = goal_configurations(space.parts, ctx, np.asarray(world.initial, dtype=float), rel, goal)
    assert len(found) >= 2
    outs = []
    for q in found:
        way = way_out(space.parts, checker, Mode.held(rel[None]), q)
        held = space.held_object_poses(np.vstack([q[None], q[None] if way is None else way[-1:]]), rel)
        outs.append(float(np.linalg.norm(held[1, :3] - held[0, :3])))
    assert outs[0] > 0.1  # the first slides the object out of the cubby (and so comes in that way)
    assert min(outs) < 0.05  # another can only lift it under the ceiling: found, but not first


def test_regrasps_in_place_try_the_goal_grasps_nearest_the_goal_first() -> None:
    made = generate_spatial("spatial_bin_cubby", 401, "ur5")
    world = made.world()
    space = SpatialSpace(world)
    assert world.object is not None
    aims = space.regrasp_aims(np.asarray(world.object.goal, dtype=float))
    goal_grasps = aims.goal_grasps()
    others = [g for g in range(space.grasp_count) if g not in goal_grasps]
    assert len(goal_grasps) >= 2
    assert others
    first = next(s for s in made.witness.segments if s.kind == "transfer")  # out of the bin, onto the table
    assert first.grasp is not None
    on_table = space.held_object_poses(first.waypoints[-1:], space.grasp_rel(first.grasp))[0]
    landmark = Landmark(1, 0, first.waypoints[-1], on_table, first.grasp, None, None, None)
    ranked = aims.ranked(landmark, [*others, *goal_grasps[::-1]])
    served = ranked[: len(goal_grasps)]
    assert set(served) == set(goal_grasps)
    takes = [aims.take_cost(g, landmark.object_pose) for g in served]
    assert takes == sorted(takes)
    assert np.isfinite(takes[0])  # a goal grasp takes the object on the table
    assert ranked[len(goal_grasps) :] == others


@pytest.mark.parametrize(("rise", "drags"), [(0.002, True), (-0.15, False)])
def test_an_object_carried_under_a_board_does_not_drag_on_it(rise: float, drags: bool) -> None:
    world = generated("spatial_bin_cubby", 0).world()
    assert world.object is not None
    goal = pose_matrix(list(world.object.goal))  # resting on the cubby's board
    poses = np.repeat(goal[None], 6, axis=0)
    poses[:, 0, 3] += np.linspace(0.0, 0.03, 6)  # 3 cm along x ...
    poses[:, 2, 3] += rise  # ... just above the board, or well under it
    moved = [m for name, _, _, m in slides(world, poses, DragSettings()) if name == world.object.goal_on[0]]
    assert (max(moved, default=0.0) > DragSettings().slide_m) is drags


def test_a_lifted_object_slides_level_in_short_moves() -> None:
    made = generate_spatial("spatial_table", 0, "panda")
    world = made.world()
    space = SpatialSpace(world)
    transfer = next(s for s in made.witness.segments if s.kind == "transfer")
    assert transfer.grasp is not None
    rel = space.grasp_rel(transfer.grasp)
    checker = space.transfer_checker(rel)
    q = np.asarray(transfer.waypoints[len(transfer.waypoints) // 2], dtype=float)  # in the air, mid-transfer
    shift = np.array([0.02, -0.01, 0.0])
    way = slid_level(space, q, shift, 4, checker)
    assert way is not None
    assert len(way) == 5
    tcps = space.tcp(np.array(way))
    assert np.allclose(tcps[-1, :3, 3] - tcps[0, :3, 3], shift, atol=1e-4)  # moved by the shift, level
    assert np.allclose(np.diff(tcps[:, :3, 3], axis=0), shift / 4, atol=1e-4)  # in equal short moves
    assert slid_level(space, q, np.zeros(3), 4, checker) is None  # nothing to slide


def test_placements_are_drawn_again_near_those_one_grasp_holds() -> None:
    """A random arm holds the object by its first grasp on few drawn placements, none shared with a goal grasp:
    the placements drawn again near those either grasp holds give one both hold."""
    made = generate_spatial("spatial_bin_cubby", 2, "random")
    world = made.world()
    assert world.object is not None
    first = next(s for s in made.witness.segments if s.kind == "transfer")
    assert first.grasp is not None
    start = Landmark(0, None, np.asarray(first.waypoints[0]), np.asarray(world.object.initial), None, None, None, None)
    found = {}
    for draws in (0, 8):
        space = SpatialSpace(
            world,
            replace(SpatialTuning(), regrasp=replace(SpatialTuning().regrasp, refine_draws=draws, solve_keep=0)),
        )
        aims = space.regrasp_aims(np.asarray(world.object.goal, dtype=float))
        found[draws] = aims.placements(start, first.grasp, np.asarray(first.waypoints[0]))
    assert found[0] == []  # the first draw: no placement both grasps hold
    assert found[8]
    for pose in found[8][:3]:  # each a stable placement on a support
        assert rests(world, np.asarray(pose))


def test_placements_drawn_near_a_pose_stay_near_it() -> None:
    world = generated("spatial_bin_cubby", 0).world()
    assert world.object is not None
    table = next(s for s in world.supports if s.name == "table")
    thing = world.object.shape
    base = sample_placements(thing, table, "-z", world.obstacles, count=1, rng=np.random.default_rng(0))[0]
    near = sample_placements(
        thing, table, "-z", world.obstacles, count=16, rng=np.random.default_rng(1), around=(base, 0.02, 0.3)
    )
    assert len(near)
    assert np.all(np.abs(near[:, :2, 3] - base[:2, 3]) <= 0.02 + 1e-12)
    assert np.allclose(near[:, 2, 3], base[2, 3])  # on the same face, on the same support
    turn = [abs(math.remainder(face_yaw(p[:3, :3], "-z") - face_yaw(base[:3, :3], "-z"), 2 * math.pi)) for p in near]
    assert max(turn) <= 0.3 + 1e-9
