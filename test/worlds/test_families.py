"""Every family of generated worlds, several seeds: the file is a world as users write them, start and
goal are valid, the witness validates at 0.002 rad, the layout is near the motion, the unsolvable
family's goal is enclosed, and the same seed gives the same bytes."""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.ops import polylabel

from clew_ros.core.parameters import WORLD_PARAMETERS
from clew_ros.core.plan import Plan
from clew_ros.planar.collision import check_start_and_goal
from clew_ros.planar.kinematics import joint_positions, transform_points
from clew_ros.planar.plan import replay, validate_plan
from clew_ros.planar.world import World, read_parameter_file, world_from_parameters
from clew_ros.worlds import FAMILIES, UnknownFamilyError, generate, separation, witness_path, world_text, write_world
from clew_ros.worlds.shapes import SHAPES

ROOT = Path(__file__).resolve().parents[2]
SEEDS = (0, 1, 2)
SOLVABLE = [name for name, family in FAMILIES.items() if family.solvable]
CASES = list(itertools.product(FAMILIES, SEEDS))
SOLVABLE_CASES = [(family, seed) for family, seed in CASES if family in SOLVABLE]


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> dict[tuple[str, int], Path]:
    """Every family and seed of :data:`CASES`, generated once and written as a user would get it."""
    directory = tmp_path_factory.mktemp("generated")
    paths = {}
    for family, seed in CASES:
        path = directory / f"{family}_{seed}.yaml"
        write_world(generate(family, seed), path)
        paths[family, seed] = path
    return paths


def load(path: Path) -> World:
    """What clew_plan does with a world file: read, parse, check start and goal."""
    return check_start_and_goal(world_from_parameters(read_parameter_file(path)))


def test_the_families_cover_what_the_issue_asks() -> None:
    assert len(SOLVABLE) >= 6
    joints = {n for name in SOLVABLE for n in FAMILIES[name].joints}
    assert {2, 7} <= joints
    assert {10, 15, 40} <= joints  # the snake family: 15 to 40 joints
    assert FAMILIES["shapes2"].joints == (2,)
    assert FAMILIES["arm7"].joints == (7,)
    assert "clutter" in SOLVABLE
    assert {kind for name in SOLVABLE for kind in FAMILIES[name].shapes} == set(SHAPES)
    assert not FAMILIES["unsolvable"].solvable


@pytest.mark.parametrize(("family", "seed"), CASES)
def test_the_file_is_a_world_with_a_valid_start_and_goal(written: dict, family: str, seed: int) -> None:
    path = written[family, seed]
    world = load(path)
    assert world.name == f"{family}_{seed}"
    text = path.read_text()
    expected = "solvable" if FAMILIES[family].solvable else "unsolvable"
    assert f"# expected: {expected}\n" in text
    # only the contract's keys: the node refuses parameters it does not know
    tree = read_parameter_file(path)
    assert set(tree) == {"world"}
    known = {key.split(".")[0] for key in WORLD_PARAMETERS} | {"name", "obstacle_names", "obstacles"}
    assert set(tree["world"]) <= known
    assert set(tree["world"]["robot"]) <= {key.split(".")[1] for key in WORLD_PARAMETERS if key.startswith("robot.")}
    assert set(tree["world"]["object"]) <= {key.split(".")[1] for key in WORLD_PARAMETERS if key.startswith("object.")}
    assert 2 <= world.robot.dof <= 40
    assert world.robot.dof in FAMILIES[family].joints
    assert len(world.object.grasps) >= 3
    assert np.all(world.robot.joint_lower < world.robot.joint_upper)


@pytest.mark.parametrize(("family", "seed"), SOLVABLE_CASES)
def test_the_witness_validates_and_carries_the_object_to_the_goal(written: dict, family: str, seed: int) -> None:
    path = written[family, seed]
    world = load(path)
    witness = Plan.read(witness_path(path))
    assert witness.success
    assert validate_plan(world, witness, step_rad=0.002) == []
    assert witness.grasp_count >= 1
    assert witness.stats["expected"] == "solvable"
    assert witness.stats["transfers"] == witness.grasp_count
    start, goal = world.object.initial, world.object.goal
    assert np.hypot(*(goal[:2] - start[:2])) >= 0.3  # the object really moves


def _obstacle_distances(world: World, witness: Plan) -> np.ndarray:
    """Each obstacle's smallest distance (m) to the arm's links (capsules) and to the object along the
    witness, sampled every 0.002 rad."""
    lines, polygons = [], []
    for motion in replay(world, witness):
        points = joint_positions(world.robot, motion.configurations)
        lines.append(shapely.linestrings(points))
        polygons.append(shapely.polygons(transform_points(motion.object_poses, world.object.polygon)))
    obstacles = shapely.polygons(np.array([o.vertices for o in world.obstacles], dtype=object).tolist())
    nearest = np.full(len(obstacles), np.inf)
    for geometries, radius in ((np.concatenate(lines), world.robot.link_width / 2), (np.concatenate(polygons), 0.0)):
        (which, _), distance = shapely.STRtree(geometries).query_nearest(obstacles, return_distance=True)
        np.minimum.at(nearest, which, distance - radius)
    return nearest


@pytest.mark.parametrize(("family", "seed"), SOLVABLE_CASES)
def test_the_layout_is_close_to_the_witness_and_keeps_its_margin(written: dict, family: str, seed: int) -> None:
    path = written[family, seed]
    world = load(path)
    assert world.obstacles
    distances = _obstacle_distances(world, Plan.read(witness_path(path)))
    nearest, farthest = float(distances.min()), float(distances.max())
    margin = FAMILIES[family].margin_m
    assert nearest >= 0.5 * margin  # every obstacle keeps clear of the whole motion, not only the samples
    assert nearest <= 2 * margin  # and the layout is built around it: some obstacle is as close as allowed
    assert farthest <= 1.0  # no obstacle stands far away from everything that moves


@pytest.mark.parametrize("seed", SEEDS)
def test_the_unsolvable_goal_is_enclosed(written: dict, seed: int) -> None:
    path = written["unsolvable", seed]
    world = load(path)
    witness = Plan.read(witness_path(path))
    assert not witness.success
    assert witness.stats["expected"] == "unsolvable"
    assert validate_plan(world, witness) == []  # a well-formed failed plan
    assert separation(world) is not None
    # Independently: the obstacles grown by the object's inscribed radius (from polylabel) have a hole
    # that holds the goal's disc centre but not the start's, so the disc, and the object, cannot get in.
    polygon = shapely.Polygon(world.object.polygon)
    centre = polylabel(polygon, 1e-4)
    radius = 0.99 * polygon.exterior.distance(centre)
    grown = shapely.union_all([shapely.Polygon(o.vertices) for o in world.obstacles]).buffer(radius)
    holes = [shapely.Polygon(ring) for part in getattr(grown, "geoms", [grown]) for ring in part.interiors]
    centre_at = {
        name: shapely.Point(transform_points(pose, np.array(centre.coords))[0])
        for name, pose in (("start", world.object.initial), ("goal", world.object.goal))
    }
    enclosing = [hole for hole in holes if hole.contains(centre_at["goal"])]
    assert enclosing, "the goal is not inside a closed ring of grown obstacles"
    assert not any(hole.contains(centre_at["start"]) for hole in enclosing)
    # and the goal itself is a valid placement inside the ring
    assert shapely.Polygon(transform_points(world.object.goal, world.object.polygon)).within(
        enclosing[0].buffer(radius)
    )


@pytest.mark.parametrize("family", list(FAMILIES))
def test_same_seed_same_bytes(written: dict, family: str) -> None:
    again = generate(family, 1)
    path = written[family, 1]
    assert world_text(again) == path.read_text()
    assert again.witness.to_json() == witness_path(path).read_text()


@pytest.mark.parametrize("family", list(FAMILIES))
def test_different_seeds_differ(written: dict, family: str) -> None:
    texts = [written[family, seed].read_text() for seed in SEEDS]
    bodies = [
        text.split("clew_planner:", 1)[1].replace(f"{family}_{seed}", "")
        for text, seed in zip(texts, SEEDS, strict=True)
    ]
    assert len(set(bodies)) == len(SEEDS)


def test_same_bytes_in_another_process(written: dict, tmp_path: Path) -> None:
    output = tmp_path / "again.yaml"
    done = subprocess.run(
        [sys.executable, "-m", "clew_ros.cli.world", "window", "--seed", "2", "-o", str(output)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
        env={**os.environ, "PYTHONHASHSEED": "12345"},
    )
    assert done.returncode == 0, done.stderr
    assert output.read_bytes() == written["window", 2].read_bytes()
    assert witness_path(output).read_bytes() == witness_path(written["window", 2]).read_bytes()
    assert json.loads(witness_path(output).read_text())["format"] == "clew-plan/1"


def test_an_unknown_family_is_named() -> None:
    with pytest.raises(UnknownFamilyError, match=r"'shelf'.*shapes2, regrasp2, pocket, shelves"):
        generate("shelf", 0)


@pytest.mark.parametrize("seed", [-1, 1.5, True])
def test_a_bad_seed_is_refused(seed: object) -> None:
    with pytest.raises(ValueError, match="seed: expected an integer >= 0"):
        generate("shapes2", seed)  # type: ignore[arg-type]
