"""The spatial example worlds under config/spatial/: each loads as clew_plan reads it, and its witness plan
(shipped next to it) validates at 0.002 rad; the motion-only query reads its MoveIt scene file."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from clew_ros.core.plan import Plan
from clew_ros.planar.world import read_parameter_file
from clew_ros.spatial.plan import validate_plan
from clew_ros.spatial.world import SpatialWorld, spatial_world_from_parameters

from .conftest import CONFIG

EXAMPLES = ("panda_table_to_table", "panda_table_to_shelf", "panda_scene_motion")


def load(name: str) -> tuple[SpatialWorld, Plan]:
    path = CONFIG / "spatial" / f"{name}.yaml"
    world = spatial_world_from_parameters(read_parameter_file(path), path.parent)
    return world, Plan.read(path.with_name(f"{name}.witness.json"))


@pytest.mark.parametrize("name", EXAMPLES)
def test_each_example_loads_and_its_witness_validates(name: str) -> None:
    world, witness = load(name)
    assert world.name == name
    assert world.robot.joint_names[0] == "panda_joint1"
    assert witness.success
    assert witness.world_kind == "spatial"
    assert validate_plan(world, witness) == []
    if world.object is not None:
        assert witness.grasp_count == 1
        assert world.object.initial_on[0] != world.object.goal_on[0]
        # no accident of the checker: without the fingers' leave to touch the object it is refused
        fingerless = replace(world, robot=replace(world.robot, gripper_links=()))
        assert any("touches the object where it rests" in p for p in validate_plan(fingerless, witness))


def test_the_pick_and_place_examples() -> None:
    table, _ = load("panda_table_to_table")
    assert table.object is not None
    assert (table.object.initial_on, table.object.goal_on) == (("table_a", "-z"), ("table_b", "-z"))
    shelf, witness = load("panda_table_to_shelf")
    assert shelf.object is not None
    assert shelf.object.goal_on == ("shelf_board", "-z")
    assert {"shelf_lid", "shelf_left", "shelf_right"} <= {o.name for o in shelf.obstacles}
    assert witness.segments[1].grasp == 1  # from the side: the lid leaves no room to come from above


def test_the_motion_only_example_reads_its_scene_file() -> None:
    world, witness = load("panda_scene_motion")
    assert world.object is None
    assert world.goal is not None
    assert [o.name for o in world.obstacles] == ["table", "cage_0", "cage_1", "cage_2"]
    table = world.obstacles[0]
    assert np.allclose(table.pose[:3, 3], [0.55, 0.0, -0.02])  # in panda_link0, which is at the origin
    assert witness.final_object_pose is None
    assert np.allclose(witness.segments[-1].waypoints[-1], world.goal)
    assert not world.checker.static_collision


def test_the_examples_are_installed() -> None:
    setup = (Path(__file__).resolve().parents[2] / "setup.py").read_text()
    assert '"share/" + package_name + "/config/spatial"' in setup
    for name in EXAMPLES:
        assert (CONFIG / "spatial" / f"{name}.witness.json").is_file()
