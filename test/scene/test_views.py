"""The three views of a scene colour each item alike: the RViz markers and the Foxglove entities take the
palette's colours (the picture's are checked in test_scene.py)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("rclpy")
pytest.importorskip("foxglove")

from helpers.foxglove_client import protobuf_decoder

from clew_ros.core.plan import PlanLandmark
from clew_ros.live import messages as live
from clew_ros.planar.world import load_world
from clew_ros.ros import messages as ros
from clew_ros.scene import PALETTE, colour

CONFIG = Path(__file__).resolve().parents[2] / "config"
NOW_NS = 1_700_000_000_000_000_000


@pytest.fixture(scope="module")
def world():
    return load_world(CONFIG / "figure1.yaml")


def rgb(color: Any) -> tuple[int, int, int]:
    """A message colour (0-1 a channel; a ROS message or a decoded Foxglove dict) as the palette's 0-255."""
    if isinstance(color, dict):
        return tuple(round(color.get(c, 0.0) * 255) for c in "rgb")  # type: ignore[return-value]
    return (round(color.r * 255), round(color.g * 255), round(color.b * 255))


def entities(update: Any) -> dict[str, Any]:
    """The entities of a Foxglove ``SceneUpdate``, by id, decoded from the schema it carries (as a client does)."""
    schema = update.get_schema()
    return {e["id"]: e for e in protobuf_decoder(schema.name, schema.data)(update.encode())["entities"]}


def test_rviz_and_foxglove_colour_the_world_from_the_palette(world) -> None:
    markers = {(m.ns, m.id): m for m in ros.world_markers(world, NOW_NS).markers if m.ns}
    entities_ = entities(live.world_update(world, NOW_NS))
    expected = {
        "bounds": ("bounds", "field_edge"),
        "obstacles": ("obstacles", "obstacle"),
        "obstacle_outlines": ("obstacles", "obstacle_edge"),
        "object_start": ("start", "start"),
        "object_goal": ("goal", "goal"),
        "grasps": ("start", "grasp"),
    }
    for ns, (_entity, key) in expected.items():
        assert rgb(markers[(ns, 0)].color) == colour(key, dark_background=True).rgb, ns
    assert rgb(entities_["bounds"]["lines"][0]["color"]) == colour("field_edge", dark_background=True).rgb
    assert rgb(entities_["obstacles"]["triangles"][0]["color"]) == PALETTE["obstacle"].rgb
    assert rgb(entities_["obstacles"]["lines"][0]["color"]) == PALETTE["obstacle_edge"].rgb
    assert rgb(entities_["start"]["lines"][0]["color"]) == PALETTE["start"].rgb
    assert rgb(entities_["start"]["spheres"][0]["color"]) == PALETTE["grasp"].rgb
    assert rgb(entities_["goal"]["lines"][0]["color"]) == PALETTE["goal"].rgb


@pytest.mark.parametrize("gripper", [0.0, 1.0])
def test_rviz_and_foxglove_colour_the_arm_the_gripper_and_the_object_alike(world, gripper) -> None:
    q = np.array(world.robot.initial, dtype=float)
    pose = np.array(world.object.initial, dtype=float)
    markers = {m.ns: m for m in ros.scene_markers(world, q, gripper, pose, NOW_NS).markers}
    entities_ = entities(live.arm_update(world, q, gripper, pose, NOW_NS))
    gripper_key, object_key = ("closed", "object_held") if gripper else ("open", "object_rest")
    assert (
        rgb(markers["arm"].color)
        == rgb(entities_["arm"]["lines"][0]["color"])
        == colour("arm", dark_background=True).rgb
    )
    assert rgb(markers["arm_joints"].color) == rgb(entities_["arm"]["spheres"][0]["color"]) == PALETTE["joint"].rgb
    assert rgb(markers["gripper"].color) == rgb(entities_["arm"]["spheres"][-1]["color"]) == PALETTE[gripper_key].rgb
    assert rgb(markers["object"].color) == rgb(entities_["object"]["lines"][0]["color"]) == PALETTE[object_key].rgb


def test_rviz_and_foxglove_colour_the_landmark_tree_from_the_palette(world) -> None:
    marks = [
        PlanLandmark(0, None, np.zeros(3), np.array(world.object.initial, dtype=float), None),
        PlanLandmark(1, 0, np.zeros(3), np.array([0.1, -0.3, 0.2]), None),
    ]
    markers = {(m.ns, m.id): m for m in ros.landmark_markers(marks, NOW_NS, world.object.polygon).markers if m.ns}
    spheres = markers[("landmarks", 0)]
    assert [rgb(c) for c in spheres.colors] == [PALETTE["start"].rgb, PALETTE["tree_node"].rgb]  # the root: start
    assert rgb(markers[("tree_edges", 0)].color) == PALETTE["tree_edge"].rgb
    assert rgb(markers[("landmark_outlines", 1)].color) == PALETTE["tree_node"].rgb
    assert rgb(markers[("landmark_ids", 1)].color) == PALETTE["label"].rgb
    entity = entities(live.landmarks_update(world, marks, NOW_NS))["landmarks"]
    assert {rgb(line["color"]) for line in entity["lines"]} == {PALETTE["tree_edge"].rgb}
    assert {rgb(sphere["color"]) for sphere in entity["spheres"]} == {PALETTE["tree_node"].rgb}


def test_the_3d_views_lighten_what_a_dark_background_would_swallow() -> None:
    for key in ("arm", "field_edge"):
        light, dark = PALETTE[key], colour(key, dark_background=True)
        assert sum(dark.rgb) > sum(light.rgb) + 150, key  # far lighter than the picture's colour
    assert colour("goal", dark_background=True) == PALETTE["goal"]  # every other key: one colour everywhere
