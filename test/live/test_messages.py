"""Core values as Foxglove messages: encoded by foxglove-sdk, decoded from their own schema, geometry checked."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("foxglove")
pytest.importorskip("google.protobuf")

from helpers.foxglove_client import protobuf_decoder

from clew_ros.core.tree import LandmarkTree
from clew_ros.live import messages
from clew_ros.planar.kinematics import joint_positions, transform_points
from clew_ros.planar.world import load_world

CONFIG = Path(__file__).resolve().parents[2] / "config"
NOW_NS = 1_700_000_000_123_456_789


def decoded(message: Any) -> dict[str, Any]:
    """``message`` encoded by the SDK, then decoded from the schema it carries (as a client does)."""
    schema = message.get_schema()
    assert schema.encoding == "protobuf"
    return protobuf_decoder(schema.name, schema.data)(message.encode())


def xy(points: list[dict[str, float]]) -> np.ndarray:
    return np.array([[p["x"], p["y"]] for p in points])


def entities(update: dict[str, Any]) -> dict[str, dict[str, Any]]:
    return {e["id"]: e for e in update["entities"]}


@pytest.fixture(scope="module")
def world():
    return load_world(CONFIG / "figure1.yaml")


def test_the_world_shows_bounds_obstacles_start_with_grasps_and_goal(world) -> None:
    scene = entities(decoded(messages.world_update(world, NOW_NS)))
    assert set(scene) == {"bounds", "obstacles", "start", "goal"}
    for entity in scene.values():
        assert entity["frame_id"] == messages.FRAME
        assert entity["timestamp"] == "2023-11-14T22:13:20.123456789Z"
    xmin, ymin, xmax, ymax = world.bounds
    assert xy(scene["bounds"]["lines"][0]["points"]).tolist() == [
        [xmin, ymin],
        [xmax, ymin],
        [xmax, ymax],
        [xmin, ymax],
    ]
    outlines = [xy(line["points"]) for line in scene["obstacles"]["lines"]]
    assert [o.tolist() for o in outlines] == [o.vertices.tolist() for o in world.obstacles]
    # each obstacle filled: triangles covering exactly its area
    for fill, obstacle in zip(scene["obstacles"]["triangles"], world.obstacles, strict=True):
        corners = xy(fill["points"]).reshape(-1, 3, 2)
        a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
        u, v = b - a, c - a
        area = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]).sum() / 2
        x, y = obstacle.vertices.T
        assert area == pytest.approx(abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))) / 2)
    start = transform_points(world.object.initial, world.object.polygon)
    assert np.allclose(xy(scene["start"]["lines"][0]["points"]), start)
    grasps = transform_points(world.object.initial, world.object.grasps)
    dots = np.array([[s["pose"]["position"]["x"], s["pose"]["position"]["y"]] for s in scene["start"]["spheres"]])
    assert np.allclose(dots, grasps)
    assert np.allclose(
        xy(scene["goal"]["lines"][0]["points"]), transform_points(world.object.goal, world.object.polygon)
    )
    other_goal = np.array([1.0, -1.0, 0.5])
    moved = entities(decoded(messages.world_update(world, NOW_NS, goal=other_goal)))
    assert np.allclose(xy(moved["goal"]["lines"][0]["points"]), transform_points(other_goal, world.object.polygon))


def test_the_landmark_tree_shows_a_dot_an_outline_and_an_edge_from_its_parent_per_landmark(world) -> None:
    tree = LandmarkTree(world.robot.initial, world.object.initial)
    poses = [np.array([0.5, 1.0, 0.3]), np.array([-0.5, 0.8, -1.0]), np.array([0.0, -1.0, 1.2])]
    for pose, parent in zip(poses, [0, 1, 0], strict=True):
        tree.add(
            parent=parent,
            joints=world.robot.initial,
            object_pose=pose,
            grasp=0,
            grasp_rel=None,
            transit=None,
            transfer=None,
        )
    (entity,) = decoded(messages.landmarks_update(world, tree, NOW_NS))["entities"]
    assert entity["id"] == "landmarks"
    all_poses = np.array([lm.object_pose for lm in tree])
    dots = np.array([[s["pose"]["position"]["x"], s["pose"]["position"]["y"]] for s in entity["spheres"]])
    assert np.allclose(dots, all_poses[:, :2])
    outlines, edges = entity["lines"]
    assert outlines["type"] == edges["type"] == "LINE_LIST"
    sides = xy(outlines["points"]).reshape(len(tree), -1, 2, 2)
    for placed, pose in zip(sides, all_poses, strict=True):
        assert np.allclose(placed[:, 0], transform_points(pose, world.object.polygon))
    pairs = xy(edges["points"]).reshape(-1, 2, 2)
    expected = [[all_poses[p, :2], all_poses[c, :2]] for c, p in [(1, 0), (2, 1), (3, 0)]]
    assert np.allclose(pairs, expected)


def test_an_empty_tree_draws_nothing(world) -> None:
    (entity,) = decoded(messages.landmarks_update(world, [], NOW_NS))["entities"]
    assert entity["spheres"] == []
    assert [line["points"] for line in entity["lines"]] == [[]]


def test_the_arm_is_its_chain_with_the_gripper_and_the_object_where_it_is(world) -> None:
    joints = np.array([0.4, -1.1])
    pose = np.array([0.3, 0.2, 0.7])
    scene = entities(decoded(messages.arm_update(world, joints, 1.0, pose, NOW_NS)))
    chain = joint_positions(world.robot, joints[None])[0]
    assert np.allclose(xy(scene["arm"]["lines"][0]["points"]), chain)
    tip = scene["arm"]["spheres"][-1]
    assert np.allclose([tip["pose"]["position"]["x"], tip["pose"]["position"]["y"]], chain[-1])
    held, resting = tip["color"], entities(decoded(messages.arm_update(world, joints, 0.0, pose, NOW_NS)))
    assert held != resting["arm"]["spheres"][-1]["color"]  # red holding, green open
    assert np.allclose(xy(scene["object"]["lines"][0]["points"]), transform_points(pose, world.object.polygon))


def test_joint_states_name_the_joints_and_the_gripper(world) -> None:
    state = decoded(messages.joint_states(world.robot.joint_names, np.array([0.25, -0.5]), 1.0, NOW_NS))
    assert [(j["name"], j["position"]) for j in state["joints"]] == [
        ("joint_1", 0.25),
        ("joint_2", -0.5),
        (messages.GRIPPER_JOINT, 1.0),
    ]
    assert state["timestamp"] == "2023-11-14T22:13:20.123456789Z"
