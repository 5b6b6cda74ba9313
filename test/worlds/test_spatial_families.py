"""The spatial families of clew_world on the Panda, the UR5 and random arms: each file loads as a user's
world, the witness validates at 0.002 rad (read back from its file), the layout is the family's, the
unsolvable family's goal is provably out of the object's way, and the same seed gives the same bytes."""

from __future__ import annotations

import functools
import itertools
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("trimesh")
pytest.importorskip("urdf_parser_py")

from clew_ros.cli.world import main
from clew_ros.core.plan import Plan
from clew_ros.planar.world import read_parameter_file
from clew_ros.spatial.inverse import InverseKinematics
from clew_ros.spatial.placements import resting_on
from clew_ros.spatial.plan import validate_plan
from clew_ros.spatial.transforms import pose_matrix
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters
from clew_ros.worlds.spatial import (
    SPATIAL_FAMILIES,
    SPATIAL_ROBOTS,
    generate_spatial,
    spatial_world_text,
    write_spatial_world,
)

CASES = [(f, r) for f, r in itertools.product(SPATIAL_FAMILIES, SPATIAL_ROBOTS) if r in SPATIAL_FAMILIES[f].robots]


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> dict[tuple[str, str], Path]:
    """Every family on every robot, seed 0, written as clew_world writes it."""
    directory = tmp_path_factory.mktemp("spatial")
    paths = {}
    for family, robot in CASES:
        path = directory / "worlds" / f"{family}_{robot}.yaml"
        write_spatial_world(generate_spatial(family, 0, robot), path)
        paths[family, robot] = path
    return paths


@functools.cache
def load(path: Path) -> tuple[SpatialWorld, Plan]:
    """The world as clew_plan reads it (its robot files relative to the file), and the witness (read once)."""
    world = spatial_world_from_parameters(read_parameter_file(path), path.parent)
    return world, Plan.read(path.with_name(path.stem + ".witness.json"))


@pytest.mark.parametrize(("family", "robot"), CASES)
def test_each_world_loads_and_its_witness_decides_it(
    written: dict[tuple[str, str], Path], family: str, robot: str
) -> None:
    path = written[family, robot]
    world, witness = load(path)
    text = path.read_text()
    assert world.name == f"{family}_{robot}_0"
    assert witness.world_kind == "spatial"
    assert world.object is not None
    if robot == "random":
        assert 4 <= world.robot.dof <= 8
        assert "description:" in text
    else:
        assert (path.parent / read_parameter_file(path)["world"]["robot"]["urdf"]).is_file()
    if SPATIAL_FAMILIES[family].solvable:
        assert text.splitlines()[1] == "# expected: solvable"
        assert witness.success
        assert validate_plan(world, witness) == []
        assert witness.grasp_count == (2 if SPATIAL_FAMILIES[family].regrasp else 1)
        assert np.linalg.norm(np.subtract(world.object.goal[:3], world.object.initial[:3])) >= 0.25
    else:
        assert text.splitlines()[1] == "# expected: unsolvable"
        assert not witness.success
        assert witness.message.startswith("no plan exists (unsolvable by construction): ")
        assert validate_plan(world, witness) == []  # a failed plan, well formed


def _names(world: SpatialWorld, prefix: str) -> list[str]:
    return [o.name for o in world.obstacles if o.name.startswith(prefix)]


@pytest.mark.parametrize("robot", SPATIAL_ROBOTS)
def test_the_layouts_are_the_families(written: dict[tuple[str, str], Path], robot: str) -> None:
    table, _ = load(written["spatial_table", robot])
    assert table.object is not None
    assert {table.object.initial_on[0], table.object.goal_on[0]} == {"table_a", "table_b"}
    assert table.object.initial_on[1] == table.object.goal_on[1] == "-z"

    shelf, _ = load(written["spatial_shelf", robot])
    assert shelf.object is not None
    assert shelf.object.goal_on[0] == "shelf"
    assert set(_names(shelf, "shelf_")) == {"shelf_lid", "shelf_left", "shelf_right"}
    lid = next(o for o in shelf.obstacles if o.name == "shelf_lid")
    assert lid.pose[2, 3] > shelf.object.goal[2]

    clutter, _ = load(written["spatial_clutter", robot])
    assert clutter.object is not None
    assert clutter.object.initial_on[0] == clutter.object.goal_on[0] == "table"
    assert len(_names(clutter, "clutter_")) >= 3

    if robot in SPATIAL_FAMILIES["spatial_bin_cubby"].robots:
        regrasp, _ = load(written["spatial_bin_cubby", robot])
        assert regrasp.object is not None
        assert regrasp.object.initial_on[0] == "bin_floor"
        assert regrasp.object.goal_on[0] == "cubby_board"
        assert {"bin_wall_px", "cubby_ceiling", "table"} <= {o.name for o in regrasp.obstacles}

        flip, _ = load(written["spatial_flip", robot])
        assert flip.object is not None
        assert flip.object.initial_on == ("table_a", "-z")
        assert flip.object.goal_on == ("table_b", "+z")  # turned over
        assert len(flip.object.grasps) == 2

        laid, _ = load(written["spatial_laid_down", robot])
        assert laid.object is not None
        assert laid.object.initial_on == ("shelf_board", "-z")
        assert laid.object.goal_on[0] == "cubby_board"
        assert laid.object.goal_on[1] in ("+x", "-x", "+y", "-y")  # lying on a side

    reorient, _ = load(written["spatial_reorient", robot])
    assert reorient.object is not None
    assert reorient.object.initial_on[1] == "-z"
    assert reorient.object.goal_on[1] != "-z"

    narrow, _ = load(written["spatial_narrow", robot])
    assert narrow.object is not None
    assert (narrow.object.initial_on[0], narrow.object.goal_on[0]) == ("shelf_a", "shelf")
    for board in ("shelf_a", "shelf"):
        top = next(s.top for s in narrow.supports if s.name == board)
        lid = next(o for o in narrow.obstacles if o.name == f"{board}_lid")
        height = narrow.object.shape.size[2] if narrow.object.shape.shape == "box" else narrow.object.shape.size[0]
        assert lid.pose[2, 3] - top < height + 0.3 + 0.05  # the lid as near as the witness allows


@pytest.mark.parametrize("robot", SPATIAL_ROBOTS)
def test_the_unsolvable_goal_is_out_of_the_objects_way(written: dict[tuple[str, str], Path], robot: str) -> None:
    world, witness = load(written["spatial_unsolvable", robot])
    assert world.object is not None
    goal = pose_matrix(world.object.goal)
    assert resting_on(world.object.shape, goal, world.supports) is not None
    walls = {o.name: o for o in world.obstacles if o.name.startswith("box_")}
    if walls:  # closed: four walls and a lid around the goal, the start outside
        assert set(walls) == {"box_north", "box_south", "box_east", "box_west", "box_lid"}
        centre = goal[:3, 3]
        assert walls["box_north"].pose[1, 3] > centre[1] > walls["box_south"].pose[1, 3]
        assert walls["box_east"].pose[0, 3] > centre[0] > walls["box_west"].pose[0, 3]
        assert walls["box_lid"].pose[2, 3] > centre[2]
        start = np.asarray(world.object.initial[:2])
        inside = (walls["box_west"].pose[0, 3] < start[0] < walls["box_east"].pose[0, 3]) and (
            walls["box_south"].pose[1, 3] < start[1] < walls["box_north"].pose[1, 3]
        )
        assert not inside
        assert "closed box" in witness.message
    else:  # out of reach: no configuration's tcp gets within a grasp's offset of the goal
        arm = world.robot
        qs = np.random.default_rng(0).uniform(arm.lower, arm.upper, size=(2000, arm.dof))
        tcp = InverseKinematics(arm).tcp_poses(qs)[:, :3, 3]
        offsets = np.linalg.norm(world.object.grasps[:, :3], axis=1).max()
        assert np.linalg.norm(tcp - goal[:3, 3], axis=1).min() > offsets + world.tolerances["goal_tolerance"]
        assert "never gets farther" in witness.message


def test_same_seed_same_bytes(tmp_path: Path) -> None:
    for robot in ("ur5", "random"):
        first = spatial_world_text(generate_spatial("spatial_clutter", 1, robot), tmp_path)
        again = generate_spatial("spatial_clutter", 1, robot)
        assert spatial_world_text(again, tmp_path) == first
        assert again.witness.to_json() == generate_spatial("spatial_clutter", 1, robot).witness.to_json()
    assert spatial_world_text(generate_spatial("spatial_clutter", 2, "ur5"), tmp_path) != first


def test_the_command_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "w" / "table.yaml"
    assert main(["spatial_table", "--robot", "ur5", "--seed", "3", "-o", str(out)]) == 0
    world, witness = load(out)
    assert world.robot.joint_names[0] == "shoulder_pan_joint"
    assert validate_plan(world, witness) == []
    assert main(["shapes2", "--robot", "ur5", "-o", str(out)]) == 2
    assert "--robot: only the spatial_* families take a robot" in capsys.readouterr().err
    assert main(["spatial_table", "--robot", "kuka", "-o", str(out)]) == 2
    assert "--robot: expected one of panda, ur5, random, got kuka" in capsys.readouterr().err
    assert main(["--list"]) == 0
    listed = capsys.readouterr().out
    assert all(name in listed for name in SPATIAL_FAMILIES)
    assert "shapes2" in listed
