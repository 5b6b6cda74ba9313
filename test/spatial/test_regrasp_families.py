"""The regrasp families that turn the object (:mod:`clew_ros.worlds.spatial_flips`): a bar turned over, a tall box
laid down in a low cubby. Each has a two-transfer witness valid on the exact geometry that does not drag the
object, and a refutation of every grasp that fails when the construction is undone."""

from __future__ import annotations

import functools
from dataclasses import replace

import pytest

pytest.importorskip("coal")

from clew_ros.spatial.handling import drag_problems
from clew_ros.spatial.placements import resting_on
from clew_ros.spatial.plan import replay, validate_plan
from clew_ros.spatial.scene import Obstacle
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld
from clew_ros.worlds.spatial import SpatialGenerated, generate_spatial
from clew_ros.worlds.spatial_regrasp import RejectedError, hand_blocked, single_grasp_refutation


@functools.cache
def generated(family: str, seed: int = 0) -> SpatialGenerated:
    return generate_spatial(family, seed, "panda")


def _rests(world: SpatialWorld, witness: SpatialGenerated) -> list[tuple[str, str]]:
    """Where the object rests (support, face) before each transit of the witness."""
    assert world.object is not None
    out = []
    for motion in replay(world, witness.witness):
        if motion.kind == "transit" and motion.object_matrices is not None:
            found = resting_on(world.object.shape, motion.object_matrices[0], world.supports)
            assert found is not None
            out.append((found[0].name, found[1]))
    return out


@pytest.mark.parametrize("family", ["spatial_flip", "spatial_laid_down"])
def test_a_turned_world_has_a_two_transfer_witness_and_no_single_grasp(family: str) -> None:
    made = generated(family)
    world = made.world()
    assert world.object is not None
    assert made.witness.grasp_count == 2
    assert validate_plan(world, made.witness) == []  # on the exact geometry, at 0.002 rad
    assert drag_problems(world, made.witness) == []
    reasons = single_grasp_refutation(world)
    assert len(reasons) == len(world.object.grasps)  # every grasp refuted, at the start or at the goal
    assert len({s.grasp for s in made.witness.segments if s.kind == "transfer"}) == 2


def test_the_flip_turns_a_bar_over_by_way_of_its_end() -> None:
    made = generated("spatial_flip")
    world = made.world()
    assert world.object is not None
    length, width, _ = world.object.shape.size
    assert length >= 2 * width
    assert width <= 0.08  # the Panda's hand opens 8 cm
    assert len(world.object.grasps) == 2  # into +z and into -z
    assert world.object.initial_on == ("table_a", "-z")
    assert world.object.goal_on == ("table_b", "+z")
    rests = _rests(world, made)
    assert rests[1][0] == "table"
    assert rests[1][1] in ("+x", "-x")  # stood on its end, where both grasps come from the side
    start = pose_matrix(list(world.object.initial))
    blocked = [hand_blocked(world.robot, start @ pose_matrix(list(g)), world.obstacles) for g in world.object.grasps]
    assert blocked == [False, True]  # from above free, from below inside the table


def _thin(obstacle: Obstacle, thickness: float) -> Obstacle:
    """A table ``thickness`` thick, its top where it was."""
    pose = obstacle.pose.copy()
    pose[2, 3] += obstacle.size[2] / 2 - thickness / 2
    return replace(obstacle, size=(*obstacle.size[:2], thickness), pose=pose)


@pytest.mark.parametrize("thickness", [None, 0.03])
def test_a_flip_on_thin_tables_lets_a_wrist_without_fingers_pass_under_them(thickness: float | None) -> None:
    """The UR5's tool sits 5 cm behind its tcp: under 3 cm tables a grasp from below meets nothing, so the grasp
    into +z (from above at the start) fits at the goal too: one transfer might do, and the proof says so."""
    world = generate_spatial("spatial_flip", 0, "ur5").world()
    if thickness is None:
        assert len(single_grasp_refutation(world)) == 2
        return
    tables = ("table_a", "table_b")
    thin = tuple(_thin(o, thickness) if o.name in tables else o for o in world.obstacles)
    with pytest.raises(RejectedError, match="grasp 0 is blocked neither"):
        single_grasp_refutation(replace(world, obstacles=thin))


def test_the_laid_down_box_stands_on_a_shelf_and_ends_lying_in_a_low_cubby() -> None:
    made = generated("spatial_laid_down")
    world = made.world()
    assert world.object is not None
    thing = world.object.shape
    assert 0.12 <= thing.size[2] <= 0.2
    assert world.object.initial_on == ("shelf_board", "-z")
    assert world.object.goal_on[0] == "cubby_board"
    assert world.object.goal_on[1] in ("+x", "-x", "+y", "-y")
    board = next(s for s in world.supports if s.name == "cubby_board")
    ceiling = next(o for o in world.obstacles if o.name == "cubby_ceiling")
    assert ceiling.pose[2, 3] - ceiling.size[2] / 2 - board.top < thing.size[2]  # it cannot stand in there
    goal = pose_matrix(list(world.object.goal))
    assert abs(goal[2, 2]) < 1e-6  # its long axis level
    transfers = [s for s in made.witness.segments if s.kind == "transfer"]
    assert transfers[1].grasp in (0, 1)  # the grasps into its end face (clew_ros.worlds.spatial_holds.grasps_of)


def test_a_laid_down_world_whose_start_shelf_opens_needs_no_regrasp() -> None:
    world = generated("spatial_laid_down").world()
    walls = ("shelf_ceiling", "shelf_back")
    opened = replace(world, obstacles=tuple(o for o in world.obstacles if o.name not in walls))
    with pytest.raises(RejectedError, match="blocked neither"):
        single_grasp_refutation(opened)  # a grasp into its end face now fits at the start too
