"""The proof of infeasibility (clew_ros.planar.passage): it refuses what it should, and never a solvable world;
`separation`, its form for the generated unsolvable worlds, likewise."""

import copy
from pathlib import Path

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from clew_ros.core.settings import Outcome, PlannerSettings
from clew_ros.planar.passage import inscribed_disc, passage_refusal, separation
from clew_ros.planar.space import plan
from clew_ros.planar.world import load_world, read_parameter_file, world_from_parameters

CONFIG = Path(__file__).resolve().parents[2] / "config"
SOLVABLE = ["figure1", "single_transfer", "arm3_regrasp", "arm5_regrasp"]


def _tree(name="single_transfer"):
    return copy.deepcopy(read_parameter_file(CONFIG / f"{name}.yaml"))


def _with_obstacles(tree, boxes):
    """``tree`` with its obstacles replaced by axis-aligned ``boxes`` (xmin, ymin, xmax, ymax)."""
    names = [f"box_{i}" for i in range(len(boxes))] or ["far"]
    if not boxes:  # a world file cannot hold an empty list: one box in a corner, far from everything
        bx = tree["world"]["bounds"]
        boxes = [(bx[0], bx[1], bx[0] + 0.01, bx[1] + 0.01)]
    tree["world"]["obstacle_names"] = names
    tree["world"]["obstacles"] = {
        name: [x0, y0, x1, y0, x1, y1, x0, y1] for name, (x0, y0, x1, y1) in zip(names, boxes, strict=True)
    }
    return tree


def test_the_ring_world_is_refused_at_once_naming_the_ring():
    world = load_world(CONFIG / "unreachable.yaml")
    reason = passage_refusal(world, world.object.goal)
    assert reason is not None
    assert "cannot pass" in reason
    for name in ("ring_south", "ring_north", "ring_west", "ring_east"):
        assert repr(name) in reason
    result = plan(world, PlannerSettings(seed=0, time_limit=5.0))
    assert result.outcome is Outcome.NO_PATH_AT_RESOLUTION
    assert result.stats["landmarks"] == 1  # answered before any exploration
    assert result.message == reason


@pytest.mark.parametrize("name", SOLVABLE)
def test_solvable_config_worlds_are_not_refused(name):
    world = load_world(CONFIG / f"{name}.yaml")
    assert passage_refusal(world, world.object.goal) is None


def test_an_object_no_grasp_of_which_is_in_reach_never_moves():
    tree = _tree()
    tree["world"]["robot"]["link_lengths"] = [0.3, 0.3]
    tree["world"]["robot"]["initial"] = [0.0, 0.0]
    world = world_from_parameters(tree)
    reason = passage_refusal(world, world.object.goal)
    assert reason is not None
    assert "never moves" in reason
    # ... unless the goal is where the object already is
    assert passage_refusal(world, world.object.initial) is None


def test_a_window_narrower_than_the_object_closes_the_way_and_a_wide_one_does_not():
    tree = _tree()
    world = world_from_parameters(tree)
    start, goal = world.object.initial, world.object.goal
    _, radius = inscribed_disc(world.object.polygon)
    # a wall along x between start and goal (start above, goal below in single_transfer? place it midway)
    y_wall = float(start[1] + goal[1]) / 2
    bounds = world.bounds
    for gap, refused in ((1.5 * radius, True), (2.5 * radius + 0.05, False)):
        x_mid = float(start[0] + goal[0]) / 2
        boxes = [
            (float(bounds[0]), y_wall - 0.02, x_mid - gap / 2, y_wall + 0.02),
            (x_mid + gap / 2, y_wall - 0.02, float(bounds[2]), y_wall + 0.02),
        ]
        walled = world_from_parameters(_with_obstacles(_tree(), boxes))
        assert (passage_refusal(walled, walled.object.goal) is not None) is refused, gap


def test_the_goal_tolerance_is_part_of_the_proof():
    """A goal closed in a thin box is refused, unless its tolerance lets the object end outside the box."""
    gx, gy = 0.0, -1.5  # single_transfer's goal
    half_x, half_y, wall = 0.25, 0.1, 0.01  # the object (0.4 x 0.12) fits inside
    boxes = [
        (gx - half_x - wall, gy - half_y - wall, gx + half_x + wall, gy - half_y),
        (gx - half_x - wall, gy + half_y, gx + half_x + wall, gy + half_y + wall),
        (gx - half_x - wall, gy - half_y, gx - half_x, gy + half_y),
        (gx + half_x, gy - half_y, gx + half_x + wall, gy + half_y),
    ]
    _, radius = inscribed_disc(world_from_parameters(_tree()).object.polygon)
    outside = half_y + wall + radius  # from the goal, the nearest place the object's disc can be outside the box
    for tolerance, refused in ((0.02, True), (outside + 0.01, False)):
        tree = _with_obstacles(_tree(), boxes)
        tree["world"]["goal_tolerance"] = tolerance
        world = world_from_parameters(tree)
        assert (passage_refusal(world, world.object.goal) is not None) is refused, tolerance


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**31 - 1),
    count=st.integers(1, 12),
)
def test_never_refuses_a_world_where_the_object_slides_straight_to_the_goal(seed, count):
    """Soundness: obstacles kept clear of the object's straight slide from start to goal never make a refusal.

    The slide is a translation, so every object point stays inside the convex hull of the object at its
    start and at its goal; boxes outside that hull leave a way. (Whether the arm could carry it does not
    matter: the proof is about the object's way alone, and must not refuse while that way exists.)
    """
    rng = np.random.default_rng(seed)
    tree = _tree()
    world = world_from_parameters(tree)
    start = np.array(world.object.initial, float)
    goal = np.array([rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), start[2]])
    corners = []
    for pose in (start, goal):
        c, s = np.cos(pose[2]), np.sin(pose[2])
        corners.append(world.object.polygon @ np.array([[c, s], [-s, c]]) + pose[:2])
    swept = shapely.MultiPoint(np.vstack(corners)).convex_hull
    bounds = world.bounds
    boxes = []
    for _ in range(200):
        if len(boxes) == count:
            break
        x, y = rng.uniform(bounds[0], bounds[2] - 0.3), rng.uniform(bounds[1], bounds[3] - 0.3)
        w, h = rng.uniform(0.05, 0.6, size=2)
        box = (x, y, min(x + w, bounds[2]), min(y + h, bounds[3]))
        if shapely.box(*box).distance(swept) > 1e-3:
            boxes.append(box)
    moved = world_from_parameters(_with_obstacles(tree, boxes))
    assert passage_refusal(moved, goal) is None


def _generated(family: str, seed: int):
    from clew_ros.worlds import generate

    return generate(family, seed)


def test_every_generated_solvable_world_passes_and_every_unsolvable_one_is_refused():
    """Soundness on worlds of every shape the generator makes (each solvable one has a validated witness)."""
    from clew_ros.worlds import family_names

    for family in family_names():
        for seed in range(3):
            generated = _generated(family, seed)
            world = generated.world()
            reason = passage_refusal(world, world.object.goal)
            if generated.solvable:
                assert reason is None, (family, seed, reason)
            elif family == "unsolvable":
                assert reason is not None, (family, seed)


def test_separation_proves_the_closed_ring_of_unreachable() -> None:
    reason = separation(load_world(CONFIG / "unreachable.yaml"))
    assert reason is not None
    assert "inscribed disc" in reason


@pytest.mark.parametrize("name", SOLVABLE)
def test_separation_never_refuses_a_solvable_world(name) -> None:
    assert separation(load_world(CONFIG / f"{name}.yaml")) is None


def test_separation_an_opening_wider_than_the_object_proves_nothing_and_a_narrower_one_does() -> None:
    tree = _tree("unreachable")
    # the object is 0.2 x 0.1 m: its inscribed disc is 0.1 m across; cut a window into the ring's north wall
    obstacles = tree["world"]["obstacles"]
    for width, proven in ((0.16, False), (0.06, True)):
        left, right = 1.1 - width / 2, 1.1 + width / 2
        obstacles["ring_north"] = [0.7, -0.9, left, -0.9, left, -0.8, 0.7, -0.8]
        obstacles["ring_north_b"] = [right, -0.9, 1.5, -0.9, 1.5, -0.8, right, -0.8]
        tree["world"]["obstacle_names"] = [*_tree("unreachable")["world"]["obstacle_names"], "ring_north_b"]
        assert (separation(world_from_parameters(tree)) is not None) == proven, width
