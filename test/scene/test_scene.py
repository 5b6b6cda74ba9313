"""The scene description: one palette, the items every view draws, the tip's path by segment kind (no ROS)."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from clew_ros.core.plan import PlanLandmark
from clew_ros.planar.kinematics import joint_positions, transform_points
from clew_ros.planar.world import load_world
from clew_ros.render.shapes import COLORS, Paint
from clew_ros.scene import (
    PALETTE,
    Colour,
    Motion,
    arm_items,
    colour,
    tree_items,
    world_items,
)

CONFIG = Path(__file__).resolve().parents[2] / "config"


@pytest.fixture(scope="module")
def world():
    return load_world(CONFIG / "figure1.yaml")


def test_a_colour_holds_four_channels_from_0_to_255_and_says_which_is_wrong() -> None:
    assert Colour(255, 0, 51).fractions() == (1.0, 0.0, 0.2, 1.0)
    assert Colour(255, 0, 51, 0).fractions(0.5) == (1.0, 0.0, 0.2, 0.5)
    assert Colour(1, 2, 3).with_alpha(40).rgba == (1, 2, 3, 40)
    with pytest.raises(ValueError, match="channel g"):
        Colour(0, 256, 0)
    with pytest.raises(ValueError, match="channel a"):
        Colour(0, 0, 0, -1)


def test_an_unknown_colour_is_named_with_the_known_ones() -> None:
    with pytest.raises(KeyError, match=r"'purple' is not a colour of the palette.*'arm'"):
        colour("purple")
    assert colour("transfer") is PALETTE["transfer"]


def test_the_picture_paints_the_palette() -> None:
    assert {key: c.rgb for key, c in PALETTE.items()} == COLORS
    assert Paint("goal", 40).rgba == (*PALETTE["goal"].rgb, 40)
    with pytest.raises(ValueError, match="'purple' is not a colour"):
        Paint("purple")


def test_the_world_items_are_the_worlds_geometry(world) -> None:
    items = world_items(world)
    xmin, ymin, xmax, ymax = world.bounds
    assert items.bounds.tolist() == [[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]]
    assert items.span == max(xmax - xmin, ymax - ymin)
    assert [o.name for o in items.obstacles] == [o.name for o in world.obstacles]
    assert [o.vertices.tolist() for o in items.obstacles] == [o.vertices.tolist() for o in world.obstacles]
    np.testing.assert_allclose(items.start, transform_points(world.object.initial, world.object.polygon))
    np.testing.assert_allclose(items.goal, transform_points(world.object.goal, world.object.polygon))
    np.testing.assert_allclose(items.grasps, transform_points(world.object.initial, world.object.grasps))
    elsewhere = np.array([0.1, -0.2, 0.5])
    np.testing.assert_allclose(world_items(world, elsewhere).goal, transform_points(elsewhere, world.object.polygon))
    for key in (items.bounds_key, items.start_key, items.goal_key, items.grasp_key, items.obstacles[0].key):
        assert key in PALETTE


def test_the_arm_items_hold_from_half_a_gripper(world) -> None:
    q = np.array(world.robot.initial, dtype=float) + 0.3
    pose = np.array([0.2, 0.1, 1.0])
    open_ = arm_items(world, q, 0.0, pose)
    np.testing.assert_allclose(open_.points, joint_positions(world.robot, q[None])[0])
    np.testing.assert_allclose(open_.object, transform_points(pose, world.object.polygon))
    assert open_.link_width == world.robot.link_width
    assert (open_.holding, open_.gripper_key, open_.object_key) == (False, "open", "object_rest")
    held = arm_items(world, q, 0.5, pose)
    assert (held.holding, held.gripper_key, held.object_key) == (True, "closed", "object_held")
    assert arm_items(world, q, True, pose).holding
    assert not arm_items(world, q, 0.49, pose).holding


def _landmark(landmark_id: int, parent: int | None, x: float) -> PlanLandmark:
    return PlanLandmark(landmark_id, parent, np.zeros(3), np.array([x, 2 * x, 0.0]), None)


def test_the_tree_is_drawn_by_landmark_id_not_by_position(world) -> None:
    # ids that are not positions: a child listed before its parent, a parent not given
    marks = [_landmark(7, 3, 1.0), _landmark(3, None, 0.5), _landmark(9, 7, 2.0), _landmark(4, 99, 3.0)]
    tree = tree_items(marks)
    assert tree is not None
    assert tree.ids == (7, 3, 9, 4)
    assert tree.parents == (3, None, 7, 99)
    assert tree.root == 1
    assert tree.nodes.tolist() == [[1.0, 2.0], [0.5, 1.0], [2.0, 4.0], [3.0, 6.0]]
    assert tree.edges.tolist() == [[[0.5, 1.0], [1.0, 2.0]], [[1.0, 2.0], [2.0, 4.0]]]
    assert tree.outlines(world).shape == (4, len(world.object.polygon), 2)
    np.testing.assert_allclose(tree.outlines(world)[2], transform_points(marks[2].object_pose, world.object.polygon))
    assert tree_items([]) is None


def _motion(held: list[int]) -> Motion:
    rows = len(held)
    q = np.linspace(0.0, 1.0, rows)[:, None] * np.ones((1, 3))
    return Motion(q, np.zeros((rows, 3)), np.array(held), np.zeros(rows, dtype=int), [])


def test_the_tip_path_is_cut_where_the_gripper_changes_and_stays_unbroken() -> None:
    motion = _motion([-1, -1, -1, 0, 0, 0, -1, -1])
    pieces = motion.tip_pieces()
    assert [(p.first, p.stop, p.kind) for p in pieces] == [(0, 4, "transit"), (3, 7, "transfer"), (6, 8, "transit")]
    for before, after in itertools.pairwise(pieces):
        assert before.stop - 1 == after.first  # the pieces share a row: no gap in the drawn path
    assert [(p.first, p.stop, p.kind) for p in motion.tip_pieces(upto=4)] == [(0, 4, "transit"), (3, 5, "transfer")]
    assert motion.tip_pieces(upto=0) == []
    assert all(p.kind in PALETTE for p in pieces)
