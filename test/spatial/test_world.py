"""clew_ros.spatial.world: a whole spatial world from its parameters, and its refusals by name."""

from __future__ import annotations

import copy
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from clew_ros.core.errors import WorldError
from clew_ros.spatial.spheres import SphereSettings
from clew_ros.spatial.world import spatial_world_from_parameters

from .conftest import CONFIG

PANDA_ON_A_TABLE: dict[str, Any] = {
    "world": {
        "kind": "spatial",
        "name": "panda_table",
        "bounds": [-1.0, -1.0, -0.2, 1.0, 1.0, 1.5],
        "robot": {
            "urdf": str(CONFIG / "robots/panda/panda.urdf"),
            "srdf": str(CONFIG / "robots/panda/panda.srdf"),
            "base_link": "panda_link0",
            "tip_link": "panda_hand_tcp",
            "initial": [0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8],
        },
        "obstacle_names": ["table"],
        "obstacles": {"table": {"shape": "box", "size": [0.6, 1.0, 0.04], "pose": [0.6, 0.0, 0.1, 0.0, 0.0, 0.0]}},
        "supports": ["table"],
        "object": {
            "shape": "box",
            "size": [0.04, 0.04, 0.12],
            "initial": [0.5, 0.2, 0.18, 0.0, 0.0, 0.3],
            "goal": [0.5, -0.2, 0.14, math.pi / 2, 0.0, 0.0],
            "grasps": [0.0, 0.0, 0.0, math.pi, 0.0, 0.0, 0.0, 0.0, 0.03, math.pi, 0.0, 0.0],
        },
    }
}


#: A coarse sphere model: these tests are about reading the world, and a coarse model builds in a blink.
COARSE = SphereSettings(cell_m=0.03, protrusion_m=0.06)


def changed(path: str, value: Any) -> dict[str, Any]:
    tree = copy.deepcopy(PANDA_ON_A_TABLE)
    node = tree["world"]
    *parents, last = path.split(".")
    for key in parents:
        node = node[key]
    if value is None:
        del node[last]
    else:
        node[last] = value
    return tree


def test_a_panda_on_a_table(tmp_path: Path) -> None:
    world = spatial_world_from_parameters(PANDA_ON_A_TABLE, tmp_path, COARSE)
    assert world.robot.dof == 7
    assert [o.name for o in world.obstacles] == ["table"]
    assert world.object is not None
    assert world.object.initial_on == ("table", "-z")
    assert world.object.goal_on == ("table", "-y")  # rolled a quarter turn about x: its -y face down
    assert world.object.grasps.shape == (2, 6)
    assert world.tolerances["placement_tolerance"] == 0.001
    assert world.tolerances["grasp_tolerance"] == 0.005
    assert world.checker.valid(world.initial[None]).tolist() == [True]


def test_a_motion_only_query(tmp_path: Path) -> None:
    tree = changed("object", None)
    tree["world"]["robot"]["goal"] = [0.5, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8]
    world = spatial_world_from_parameters(tree, tmp_path, COARSE)
    assert world.object is None
    assert world.goal is not None
    assert world.goal[0] == 0.5


@pytest.mark.parametrize(
    ("path", "value", "parameter", "message"),
    [
        ("kind", None, "world.kind", "expected spatial"),
        ("robot.initial", [0.0] * 6, "world.robot.initial", "expected 7 finite values"),
        ("robot.initial", [0.0] * 7, "world.robot.initial", "panda_joint4 = 0.0 is outside its limits"),
        ("robot.initial", None, "world.robot.initial", "missing"),
        ("object", None, "world.object", "or world.robot.goal_pose (the tcp's pose) for a motion-only query"),
        ("object.initial", [0.5, 0.2, 0.2, 0.0, 0.0, 0.3], "world.object.initial", "is not a stable placement"),
        ("object.goal", [0.5, -0.2, 0.14, 0.3, 0.0, 0.0], "world.object.goal", "is not a stable placement"),
        ("object.grasps", [0.0, 0.0, 0.2, 0.0, 0.0, 0.0], "world.object.grasps", "grasp 0"),
        ("object.grasps", [0.0] * 5, "world.object.grasps", "6 numbers each"),
        ("supports", ["shelf"], "world.supports", "'shelf' is not an obstacle"),
        ("placement_tolerance", -1.0, "world.placement_tolerance", "expected a value in [0.0, 1.0], got -1.0"),
        ("bounds", [0, 0, 0, 1, 1], "world.bounds", "6 finite numbers"),
    ],
)
def test_bad_worlds_are_refused_by_name(tmp_path: Path, path: str, value: Any, parameter: str, message: str) -> None:
    with pytest.raises(WorldError, match=re.escape(message)) as error:
        spatial_world_from_parameters(changed(path, value), tmp_path, COARSE)
    assert error.value.parameter == parameter


def test_the_scene_file_is_read_beside_the_parameters(tmp_path: Path) -> None:
    (tmp_path / "scene.yaml").write_text(
        "world:\n  collision_objects:\n    - id: post\n      header: {frame_id: panda_link0}\n"
        "      primitives: [{type: cylinder, dimensions: [1.0, 0.02]}]\n"
        "      primitive_poses: [{position: [0.0, 0.6, 0.5], orientation: [0, 0, 0, 1]}]\n"
    )
    tree = changed("scene_file", "scene.yaml")
    tree["world"]["robot"]["base_pose"] = [0.0, 0.0, 0.05, 0.0, 0.0, 0.0]
    world = spatial_world_from_parameters(tree, tmp_path, COARSE)
    assert [o.name for o in world.obstacles] == ["table", "post"]
    np.testing.assert_allclose(world.obstacles[1].pose[:3, 3], [0.0, 0.6, 0.55])
