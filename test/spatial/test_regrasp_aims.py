"""Regrasping in 3-D (issue 53), where the aims and the ways meet an enclosure: placements solved for where
none drawn is shared by two grasps, a transit over the top into a cubby, and transits that aim at postures
from which the object can be carried out."""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np
import pytest

pytest.importorskip("coal")

from clew_ros.core.settings import PlannerSettings
from clew_ros.core.space import Mode, PlanningContext
from clew_ros.core.tree import Landmark
from clew_ros.spatial.handling import drag_problems
from clew_ros.spatial.lift import lift_up
from clew_ros.spatial.plan import make_plan
from clew_ros.spatial.search import carried_out_then_in
from clew_ros.spatial.settle import rests
from clew_ros.spatial.space import SpatialSpace, plan
from clew_ros.spatial.targets import holds, movable_first
from clew_ros.spatial.tuning import SpatialTuning
from clew_ros.spatial.ways import way
from clew_ros.spatial.world import SpatialWorld
from clew_ros.worlds.spatial import SpatialGenerated, generate_spatial


@functools.cache
def generated(family: str, seed: int, robot: str) -> SpatialGenerated:
    return generate_spatial(family, seed, robot)


def _first_transfer(made: SpatialGenerated) -> tuple[int, np.ndarray]:
    first = next(s for s in made.witness.segments if s.kind == "transfer")
    assert first.grasp is not None
    return first.grasp, np.asarray(first.waypoints[0], dtype=float)


def test_placements_are_solved_for_where_none_drawn_is_held_by_both_grasps() -> None:
    """A random arm holds the object by its only grasp at the start on no placement drawn or drawn again: the
    placements solved for (level inverse kinematics at spots of each support) give ones a goal grasp holds too."""
    made = generated("spatial_cubby_bin", 500, "random")
    world = made.world()
    assert world.object is not None
    grasp, start = _first_transfer(made)
    root = Landmark(0, None, np.asarray(world.initial), np.asarray(world.object.initial), None, None, None, None)
    found = {}
    for keep in (0, 8):
        tuning = SpatialTuning()
        space = SpatialSpace(world, replace(tuning, regrasp=replace(tuning.regrasp, solve_keep=keep)))
        found[keep] = space.regrasp_aims(np.asarray(world.object.goal, dtype=float)).placements(root, grasp, start)
    assert found[0] == []
    assert found[8]
    for pose in found[8]:
        assert rests(world, np.asarray(pose))


def _holding(space: SpatialSpace, world: SpatialWorld, grasp: int) -> np.ndarray:
    """The transit targets of ``grasp`` at the object's start, from the arm's initial configuration."""
    assert world.object is not None
    ctx = PlanningContext(space, PlannerSettings(seed=0), np.random.default_rng(0))
    pose = np.asarray(world.object.initial, dtype=float)
    return holds(space.parts, ctx, np.asarray(world.initial, dtype=float), pose, grasp)


def test_a_transit_reaches_into_a_cubby_over_the_top() -> None:
    """The UR5 reaches the witness's grasp in a cubby from its start only over the top (both ends raised): the
    way is found with it, not without it (``slide_targets`` 0 turns it off), and every move of it is clear."""
    made = generated("spatial_cubby_bin", 502, "ur5")
    world = made.world()
    assert world.object is not None
    grasp, _ = _first_transfer(made)
    resting = Mode.resting(np.asarray(world.object.initial, dtype=float)[None])
    q0 = np.asarray(world.initial, dtype=float)
    found = {}
    for targets in (0, 2):
        space = SpatialSpace(world, replace(SpatialTuning(), slide_targets=targets))
        found[targets] = way(space.parts, resting, q0, _holding(space, world, grasp))
    assert found[0] is None
    assert found[2] is not None
    parts = SpatialSpace(world).parts
    path = np.vstack([q0[None], found[2]])
    assert parts.clear(parts.checker_of(resting), path[:-1], path[1:]).all()
    assert np.max(parts.tcp(path)[:, 2, 3]) > parts.tcp(q0[None])[0, 2, 3] + 0.1  # over the top


def test_holding_configurations_that_cannot_carry_the_object_out_are_dropped() -> None:
    """In a UR5's cubby, a configuration from which the object (held by the witness's grasp) cannot be carried
    ``approach_m`` out (one holding another grasp: the object, held so, is in a wall) is dropped where one
    can carry it out is among those measured; none is dropped where none can."""
    made = generated("spatial_cubby_bin", 502, "ur5")
    world = made.world()
    assert world.object is not None
    grasp, _ = _first_transfer(made)
    space = SpatialSpace(world)
    parts = space.parts
    pose = np.asarray(world.object.initial, dtype=float)
    good = _holding(space, world, grasp)
    assert len(good)
    other = next(g for g in range(space.grasp_count) if g != grasp and len(_holding(space, world, g)))
    stuck = _holding(space, world, other)[0]
    kept = movable_first(parts, np.vstack([stuck, good[0]]), pose, grasp)
    assert len(kept) == 1
    assert np.allclose(kept[0], good[0])
    alone = movable_first(parts, stuck[None], pose, grasp)
    assert len(alone) == 1  # none carries it out: as they were


def test_a_transfer_carries_the_object_out_of_a_cubby_then_in_to_its_target() -> None:
    """From the witness's grasp in a UR5's cubby, the object's way out and then straight moves reach the
    configuration that sets it down on the table: every move clear with the object held, the object out of
    the cubby on the way (its way out carries it ``approach_m`` at least)."""
    made = generated("spatial_cubby_bin", 502, "ur5")
    world = made.world()
    first = next(s for s in made.witness.segments if s.kind == "transfer")
    assert first.grasp is not None
    space = SpatialSpace(world)
    parts = space.parts
    rel = space.grasp_rel(first.grasp)
    q0, target = np.asarray(first.waypoints[0]), np.asarray(first.waypoints[-1])
    path = carried_out_then_in(parts, q0, rel, target[None], np.random.default_rng(0))
    assert path is not None
    assert np.allclose(path[-1], target)
    points = np.vstack([q0[None], path])
    assert parts.clear(parts.transfer_checker(rel), points[:-1], points[1:]).all()
    carried = parts.held_object_poses(points, rel)
    assert np.max(np.linalg.norm(carried[:, :3] - carried[0, :3], axis=1)) >= parts.tuning.approach_m


def test_an_arm_that_cannot_keep_its_tcp_turn_still_lifts_the_object_off_level() -> None:
    """A random arm holds the object on a shelf's board where inverse kinematics finds no configuration with
    the tcp 8 mm higher and its orientation kept: the lift leaves the tcp's turn about the vertical free (the
    object stays level), so the plan's transfer lifts the object off instead of sliding it along the board."""
    made = generated("spatial_shelf_bin", 702, "random")
    world = made.world()
    result = plan(world, PlannerSettings(seed=0, time_limit=30.0))
    assert result.success, result.message
    built = make_plan(world, [(s.kind, s.grasp, s.waypoints) for s in result.segments])
    assert drag_problems(world, built) == []
    space = SpatialSpace(world)
    first = next(s for s in result.segments if s.kind == "transfer")
    assert first.grasp is not None
    start = np.asarray(first.waypoints[0], dtype=float)
    checker = space.transfer_checker(space.grasp_rel(first.grasp))
    target = space.tcp(start[None])[0].copy()
    target[2, 3] += 0.008
    whole = space.ik(1).solve_many([target], np.random.default_rng(0), seeds=[start[None]], checker=checker)[0]
    up = lift_up(space, start, 0.008, checker)
    assert up is not None
    reached = space.tcp(up[None])[0]
    assert np.allclose(reached[:3, 3], target[:3, 3], atol=1e-4)
    assert abs(float(reached[2, 2]) - float(target[2, 2])) < 1e-4  # the tcp's tilt kept
    if len(whole):
        pytest.skip("inverse kinematics found the whole pose here: the fallback was not needed")
