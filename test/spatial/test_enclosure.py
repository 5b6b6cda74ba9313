"""The closed-box proof (clew_ros.spatial.enclosure): sound on random boxes with an opening the object's
centre can pass, complete on closed ones, never refusing a generated solvable world, proving the unsolvable
family's closed boxes, and answered by the planner at once."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from clew_ros.core.settings import Outcome, PlannerSettings
from clew_ros.planar.world import read_parameter_file
from clew_ros.spatial.enclosure import enclosure_refusal, inscribed_radius, obstacle_distance
from clew_ros.spatial.placements import MovableObject
from clew_ros.spatial.scene import Obstacle
from clew_ros.spatial.space import plan
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters
from clew_ros.worlds.spatial import SPATIAL_FAMILIES, generate_spatial

from .conftest import CONFIG


@pytest.fixture(scope="module")
def table_world() -> SpatialWorld:
    path: Path = CONFIG / "spatial" / "panda_table_to_table.yaml"
    return spatial_world_from_parameters(read_parameter_file(path), path.parent)


def _box(name: str, size: list[float], centre: np.ndarray, frame: np.ndarray) -> Obstacle:
    pose = frame.copy()
    pose[:3, 3] = frame[:3, :3] @ centre + frame[:3, 3]
    return Obstacle(name, "box", tuple(size), pose)


def _crate(rng: np.random.Generator, thing: MovableObject, frame: np.ndarray, hole: float) -> list[Obstacle]:
    """A floor, four walls and a lid around the origin of ``frame`` (the object's centre, resting on the floor),
    the lid split about a square hole ``hole`` m wide at (0, 0) (0: closed)."""
    height = thing.size[2] if thing.shape == "box" else thing.size[0]
    reach = float(np.linalg.norm(thing.size[:2])) if thing.shape == "box" else thing.size[1]
    half = reach / 2 + rng.uniform(0.0, 0.05) if thing.shape == "box" else reach + rng.uniform(0.0, 0.05)
    t = rng.uniform(0.004, 0.03)
    top = height / 2 + rng.uniform(0.0, 0.06)  # the lid's underside over the centre
    bottom = -height / 2  # the floor's top
    span = 2 * (half + t)
    out = [
        _box("floor", [span + 0.1, span + 0.1, 0.03], np.array([0, 0, bottom - 0.015]), frame),
        _box("north", [span, t, top - bottom], np.array([0, half + t / 2, (top + bottom) / 2]), frame),
        _box("south", [span, t, top - bottom], np.array([0, -half - t / 2, (top + bottom) / 2]), frame),
        _box("east", [t, 2 * half, top - bottom], np.array([half + t / 2, 0, (top + bottom) / 2]), frame),
        _box("west", [t, 2 * half, top - bottom], np.array([-half - t / 2, 0, (top + bottom) / 2]), frame),
    ]
    z = top + t / 2
    if hole <= 0:
        return [*out, _box("lid", [span, span, t], np.array([0, 0, z]), frame)]
    side = (span - hole) / 2  # four boards around the hole
    return [
        *out,
        _box("lid_n", [span, side, t], np.array([0, hole / 2 + side / 2, z]), frame),
        _box("lid_s", [span, side, t], np.array([0, -hole / 2 - side / 2, z]), frame),
        _box("lid_e", [side, hole, t], np.array([hole / 2 + side / 2, 0, z]), frame),
        _box("lid_w", [side, hole, t], np.array([-hole / 2 - side / 2, 0, z]), frame),
    ]


def _crate_world(world: SpatialWorld, rng: np.random.Generator, hole_ratio: float) -> tuple[SpatialWorld, bool]:
    """A world whose goal rests in a crate (tilted and turned at random) with a hole ``hole_ratio`` x the
    object's inscribed diameter wide in its lid (0: closed), the start above the hole; and whether the centre
    can pass: the straight line up through the hole keeps at least the proof's radius from every board."""
    assert world.object is not None
    if rng.random() < 0.5:
        thing = MovableObject("box", tuple(float(v) for v in rng.uniform([0.03, 0.03, 0.06], [0.06, 0.06, 0.14])))
    else:
        thing = MovableObject("cylinder", (float(rng.uniform(0.06, 0.14)), float(rng.uniform(0.015, 0.03))))
    frame = pose_matrix([*rng.uniform(-0.5, 0.5, 2), rng.uniform(0.1, 0.6), *rng.uniform(-0.4, 0.4, 2), 0.0])
    frame[:3, :3] = frame[:3, :3] @ pose_matrix([0, 0, 0, 0, 0, rng.uniform(-math.pi, math.pi)])[:3, :3]
    r_in = inscribed_radius(thing)
    hole = hole_ratio * 2 * r_in
    obstacles = _crate(rng, thing, frame, hole)
    start = frame @ np.array([0.0, 0.0, 0.4, 1.0])
    goal = frame[:3, 3]
    r = r_in - world.tolerances["placement_tolerance"]
    line = goal + np.linspace(0.0, 1.0, 4001)[:, None] * (start[:3] - goal)
    step = float(np.linalg.norm(start[:3] - goal)) / 4000
    clear = min(float(obstacle_distance(o, line).min()) for o in obstacles) >= r + step
    pose = [*goal, 0.0, 0.0, 0.0]
    changed = replace(
        world,
        obstacles=tuple(obstacles),
        object=replace(world.object, shape=thing, initial=(*start[:3], 0.0, 0.0, 0.0), goal=tuple(pose)),
    )
    return changed, clear


@pytest.mark.parametrize("seed", range(4))
def test_never_refuses_a_crate_the_centre_can_leave_and_proves_a_closed_one(
    table_world: SpatialWorld, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    passable = closed = 0
    for _ in range(40):
        ratio = float(rng.choice([0.0, rng.uniform(0.5, 1.6)]))  # openings near the limit: 2 r wide
        world, clear = _crate_world(table_world, rng, ratio)
        assert world.object is not None
        why = enclosure_refusal(world, np.array(world.object.goal))
        if clear:
            passable += 1
            assert why is None, why  # sound: a way out exists, so no proof
        if ratio == 0.0:
            closed += 1
            assert why is not None  # complete on a closed crate
            assert "'lid'" in why
            assert "'floor'" in why
    assert passable >= 5
    assert closed >= 5


def test_a_start_inside_the_crate_proves_nothing(table_world: SpatialWorld) -> None:
    world, _ = _crate_world(table_world, np.random.default_rng(11), 0.0)
    assert world.object is not None
    assert enclosure_refusal(world, np.array(world.object.goal)) is not None
    assert enclosure_refusal(world, np.array(world.object.goal), start=np.array(world.object.goal)) is None


def test_obstacle_distance_against_sampled_points() -> None:
    """The distance to a box, cylinder and sphere is the nearest of many points sampled inside each."""
    rng = np.random.default_rng(3)
    pose = pose_matrix([0.1, -0.2, 0.3, 0.4, -0.5, 0.6])
    for shape, size in (("box", (0.2, 0.1, 0.3)), ("cylinder", (0.3, 0.08)), ("sphere", (0.12,))):
        obstacle = Obstacle(shape, shape, size, pose)
        inside = rng.uniform(-0.2, 0.2, size=(200_000, 3))
        if shape == "box":
            inside = inside[np.all(np.abs(inside) <= np.asarray(size) / 2, axis=1)]
        elif shape == "cylinder":
            inside = inside[(np.hypot(inside[:, 0], inside[:, 1]) <= size[1]) & (np.abs(inside[:, 2]) <= size[0] / 2)]
        else:
            inside = inside[np.linalg.norm(inside, axis=1) <= size[0]]
        placed = inside @ pose[:3, :3].T + pose[:3, 3]
        queries = pose[:3, 3] + rng.uniform(-0.5, 0.5, size=(50, 3))
        computed = obstacle_distance(obstacle, queries)
        sampled = np.array([np.min(np.linalg.norm(placed - q, axis=1)) for q in queries])
        assert np.all(computed <= sampled + 1e-12)
        assert np.all(sampled - computed < 0.02)
        assert obstacle_distance(obstacle, pose[None, :3, 3])[0] == 0.0


SOLVABLE = [name for name, family in SPATIAL_FAMILIES.items() if family.solvable]


def _never_refused(family: str, robot: str, seeds: range) -> None:
    for seed in seeds:
        world = generate_spatial(family, seed, robot).world()
        assert world.object is not None
        assert enclosure_refusal(world, np.array(world.object.goal)) is None, (family, robot, seed)


@pytest.mark.parametrize("family", SOLVABLE)
def test_never_refuses_a_generated_solvable_world(family: str) -> None:
    _never_refused(family, "random" if "random" in SPATIAL_FAMILIES[family].robots else "ur5", range(1))


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["panda", "ur5", "random"])
@pytest.mark.parametrize("family", SOLVABLE)
def test_never_refuses_a_generated_solvable_world_seeds_0_to_9(family: str, robot: str) -> None:
    if robot not in SPATIAL_FAMILIES[family].robots:
        pytest.skip(f"{family} is not generated on {robot}")
    _never_refused(family, robot, range(10))


def test_proves_every_closed_box_of_the_unsolvable_family() -> None:
    boxes = 0
    for robot, seeds in (("random", range(5)), ("panda", (0, 2))):
        for seed in seeds:
            world = generate_spatial("spatial_unsolvable", seed, robot).world()
            assert world.object is not None
            why = enclosure_refusal(world, np.array(world.object.goal))
            if "box_lid" in {o.name for o in world.obstacles}:
                boxes += 1
                assert why is not None
                assert all(f"'{name}'" in why for name in ("table_b", "box_lid", "box_north", "box_west"))
            else:
                assert why is None  # out of reach: the object could get there (another proof says no)
    assert boxes >= 4


def test_the_planner_answers_a_closed_box_at_once() -> None:
    world = generate_spatial("spatial_unsolvable", 0, "random").world()
    assert "box_lid" in {o.name for o in world.obstacles}
    result = plan(world, PlannerSettings(seed=0, time_limit=30.0))
    assert result.outcome is Outcome.NO_PATH_AT_RESOLUTION
    assert result.message.startswith("no plan exists: the goal placement is closed off by")
    assert len(result.tree) == 1  # no search ran
