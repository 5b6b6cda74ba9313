"""clew_ros.spatial.scene: obstacles and bounds from parameters, refusals naming the parameter."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from clew_ros.core.errors import WorldError
from clew_ros.spatial.scene import bounds_from_parameters, obstacles_from_parameters, world_obstacles
from clew_ros.spatial.transforms import pose_matrix


def world(**obstacles: Any) -> dict[str, Any]:
    return {"obstacle_names": list(obstacles), "obstacles": obstacles}


def test_obstacles_read_as_solid_primitives() -> None:
    read = obstacles_from_parameters(
        world(
            table={"shape": "box", "size": [1.2, 0.8, 0.04], "pose": [0.5, 0.0, -0.02, 0.0, 0.0, 0.0]},
            can={"shape": "cylinder", "size": [0.12, 0.03], "pose": [0.4, 0.1, 0.06, 0.0, 0.0, math.pi / 2]},
            ball={"shape": "sphere", "size": [0.05], "pose": [0.3, -0.2, 0.3, 0.0, 0.0, 0.0]},
        )
    )
    assert [(o.name, o.shape, o.size) for o in read] == [
        ("table", "box", (1.2, 0.8, 0.04)),
        ("can", "cylinder", (0.12, 0.03)),
        ("ball", "sphere", (0.05,)),
    ]
    np.testing.assert_allclose(read[1].pose[:3, 0], [0.0, 1.0, 0.0], atol=1e-12)  # yaw pi/2 turns x onto y


@pytest.mark.parametrize(
    ("entry", "parameter", "message"),
    [
        ({"shape": "cone", "size": [1.0], "pose": [0.0] * 6}, "world.obstacles.o.shape", "box, cylinder, sphere"),
        ({"shape": "box", "size": [1.0, 1.0], "pose": [0.0] * 6}, "world.obstacles.o.size", "[x, y, z] full extents"),
        ({"shape": "cylinder", "size": [1.0, -0.1], "pose": [0.0] * 6}, "world.obstacles.o.size", "positive"),
        ({"shape": "sphere", "size": [0.1], "pose": [0.0] * 5}, "world.obstacles.o.pose", "6 finite numbers"),
        ({"shape": "sphere", "size": [0.1]}, "world.obstacles.o.pose", "missing"),
        ("box", "world.obstacles.o", "expected shape, size and pose"),
    ],
)
def test_bad_obstacles_are_refused_by_name(entry: Any, parameter: str, message: str) -> None:
    with pytest.raises(WorldError, match=re.escape(message)) as error:
        obstacles_from_parameters(world(o=entry))
    assert error.value.parameter == parameter


def test_bounds() -> None:
    assert bounds_from_parameters({}) is None
    assert bounds_from_parameters({"bounds": [-1, -1, 0, 1, 1, 2]}).tolist() == [-1, -1, 0, 1, 1, 2]
    with pytest.raises(WorldError, match=re.escape("world.bounds: expected each minimum below its maximum")):
        bounds_from_parameters({"bounds": [-1, -1, 2, 1, 1, 0]})
    with pytest.raises(WorldError, match=re.escape("world.obstacle_names: expected distinct names")):
        obstacles_from_parameters({"obstacle_names": ["a", "a"], "obstacles": {}})


MOTIONBENCHMAKER = """
name: shelf
world:
  collision_objects:
    - id: Can1
      header:
        frame_id: world
      primitives:
        - type: cylinder
          dimensions: [0.14, 0.03]
      primitive_poses:
        - position: [0.6, -0.6, 1.0]
          orientation: [0, 0, -0.4062511770401913, 0.9137614465239049]
    - id: shelf
      header:
        frame_id: base_link
      pose:
        position: {x: 1.0, y: 0.0, z: 0.0}
        orientation: {x: 0.0, y: 0.0, z: 0.0, w: 1.0}
      primitives:
        - type: 1
          dimensions: [0.4, 0.8, 0.02]
        - type: sphere
          dimensions: [0.05]
      primitive_poses:
        - position: [0.0, 0.0, 0.5]
          orientation: [0, 0, 0, 1]
        - position: [0.0, 0.0, 0.6]
          orientation: [0, 0, 0, 1]
"""


def test_a_moveit_planning_scene_file_adds_its_primitives(tmp_path: Path) -> None:
    (tmp_path / "shelf.scene.yaml").write_text(MOTIONBENCHMAKER)
    base = pose_matrix([0.0, 0.0, 0.2, 0.0, 0.0, 0.0])  # base_link 0.2 m up
    tree = {
        **world(post={"shape": "box", "size": [0.1, 0.1, 1.0], "pose": [0.0] * 6}),
        "scene_file": "shelf.scene.yaml",
    }
    read = world_obstacles(tree, tmp_path, {"base_link": base})
    assert [(o.name, o.shape, o.size) for o in read] == [
        ("post", "box", (0.1, 0.1, 1.0)),
        ("Can1", "cylinder", (0.14, 0.03)),
        ("shelf_0", "box", (0.4, 0.8, 0.02)),
        ("shelf_1", "sphere", (0.05,)),
    ]
    np.testing.assert_allclose(read[1].pose[:3, 3], [0.6, -0.6, 1.0])
    yaw = 2 * math.atan2(-0.4062511770401913, 0.9137614465239049)
    np.testing.assert_allclose(read[1].pose[:3, :3], pose_matrix([0, 0, 0, 0, 0, yaw])[:3, :3], atol=1e-12)
    np.testing.assert_allclose(read[2].pose[:3, 3], [1.0, 0.0, 0.7])  # base_link, then the object's pose
    np.testing.assert_allclose(read[3].pose[:3, 3], [1.0, 0.0, 0.8])


@pytest.mark.parametrize(
    ("change", "parameter", "message"),
    [
        (("frame_id: base_link", "frame_id: camera"), "header.frame_id", "unknown frame 'camera'"),
        (("type: sphere", "type: cone"), "primitives[1].type", "expected box, sphere or cylinder"),
        (("type: 1", "type: 4"), "primitives[0].type", "expected box, sphere or cylinder"),
        (("dimensions: [0.05]", "dimensions: [0.05, 1.0]"), "primitives[1].size", "a sphere size"),
        (("orientation: [0, 0, 0, 1]\n", "orientation: [0, 0, 0]\n"), "primitive_poses[0].orientation", "[x, y, z, w]"),
        (("id: Can1", "id: shelf_1"), "world.scene_file", "given twice: ['shelf_1']"),
        (("world:", "world: []\nnot_world:"), "world.scene_file", "expected a mapping holding collision_objects"),
    ],
)
def test_bad_scene_files_are_refused_by_name(
    tmp_path: Path, change: tuple[str, str], parameter: str, message: str
) -> None:
    (tmp_path / "s.yaml").write_text(MOTIONBENCHMAKER.replace(*change, 1))
    with pytest.raises(WorldError, match=re.escape(message)) as error:
        world_obstacles({"scene_file": "s.yaml"}, tmp_path, {"base_link": np.eye(4)})
    assert parameter in error.value.parameter or parameter in str(error.value)


def test_an_unreadable_scene_file_is_refused(tmp_path: Path) -> None:
    with pytest.raises(WorldError, match="cannot read") as error:
        world_obstacles({"scene_file": "missing.yaml"}, tmp_path)
    assert error.value.parameter == "world.scene_file"
    (tmp_path / "bad.yaml").write_text("world: {collision_objects: [")
    with pytest.raises(WorldError, match="as YAML"):
        world_obstacles({"scene_file": "bad.yaml"}, tmp_path)
