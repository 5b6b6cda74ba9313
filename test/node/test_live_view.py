"""``live.foxglove_port``: a running clew_planner mirrors its runs to a Foxglove WebSocket on 127.0.0.1.

The node runs in a subprocess; a Foxglove WebSocket client here subscribes
to every channel and decodes what it receives while ``~/plan`` runs.
"""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

pytest.importorskip("rclpy")
pytest.importorskip("foxglove")
pytest.importorskip("websockets")
pytest.importorskip("google.protobuf")

from helpers.foxglove_client import FoxgloveClient
from helpers.node_harness import NodeProcess, Session, run_id_of
from helpers.rel_node import set_parameters

pytestmark = pytest.mark.ros

QUICK = Path(__file__).parents[1] / "worlds" / "node_quick.yaml"
CHANNELS = 6


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def test_a_run_of_the_node_is_seen_live(tmp_path: Path) -> None:
    port = _free_port()
    fast = {"trajectory.max_velocity": 20.0, "trajectory.max_acceleration": 400.0, "playback.rate": 50.0}
    node = NodeProcess(tmp_path / "node.log", QUICK, {"record.enabled": False, "live.foxglove_port": port, **fast})
    session = Session(node)
    try:
        session.world_markers.wait_for(timeout_s=60.0)  # started: its world is out, after the live view
        with FoxgloveClient.connect(port, channels=CHANNELS, timeout_s=60.0) as client:
            topics = set(client.topics.values())
            assert all(topic.startswith(f"{node.name}/") for topic, _schema in topics)
            response = session.plan()
            assert response.success, response.message
            run_id = run_id_of(response.message)
            states_after_grasp: list[object] = []
            grasped = False

            def grasped_then_moved(message) -> bool:  # the grasp event, then the arm moving with the object
                nonlocal grasped
                grasped = grasped or (message.topic.endswith("/events") and message.data.get("kind") == "grasp")
                if grasped and message.topic.endswith("/joint_states"):
                    states_after_grasp.append(message)
                return len(states_after_grasp) >= 2

            received = client.receive_until(grasped_then_moved, timeout_s=60.0)
        kinds = [m.data["kind"] for m in received if m.topic.endswith("/events")]
        assert "succeeded" in kinds
        assert "grasp" in kinds
        assert any(m.data.get("run_id") == run_id for m in received if m.topic.endswith("/events"))
        assert any(m.topic.endswith("/scene") for m in received)  # the world (sent when subscribed)
        assert any(m.topic.endswith("/landmarks") for m in received)
        states = [m for m in received if m.topic.endswith("/joint_states")]
        assert len(states) >= 2  # the playback, mirrored
        # read only: taken when the node starts
        [result] = set_parameters(session, {"live.foxglove_port": port + 1})
        assert not result.successful
    finally:
        code = session.close()
    assert code == 0, node.output()
    assert f"serving runs live to Foxglove at ws://127.0.0.1:{port}" in node.output()


def test_a_spatial_run_of_the_node_is_seen_live_in_3d(tmp_path: Path) -> None:
    """The Panda table-to-table world: the scene, the links and their transforms, the playback mirrored."""
    import numpy as np
    import yaml

    from clew_ros.render.spatial.frames import load_spatial_world
    from clew_ros.spatial.transforms import quaternion_matrix

    source = Path(__file__).resolve().parents[2] / "config" / "spatial" / "panda_table_to_table.yaml"
    document = yaml.safe_load(source.read_text())
    world_tree = document["clew_planner"]["ros__parameters"]["world"]
    for key in ("urdf", "srdf"):
        world_tree["robot"][key] = str((source.parent / world_tree["robot"][key]).resolve())
    params = tmp_path / source.name
    params.write_text(yaml.safe_dump(document))
    port = _free_port()
    fast = {"trajectory.max_velocity": 20.0, "trajectory.max_acceleration": 200.0, "playback.rate": 25.0}
    node = NodeProcess(tmp_path / "node.log", params, {"record.enabled": False, "live.foxglove_port": port, **fast})
    session = Session(node)
    try:
        session.world_markers.wait_for(timeout_s=90.0)
        with FoxgloveClient.connect(port, channels=CHANNELS + 2, timeout_s=60.0) as client:
            response = session.plan(timeout_s=60.0)
            assert response.success, response.message
            after_grasp: list[object] = []
            grasped = False

            def grasped_then_moved(message) -> bool:  # the grasp event, then the arm moving with the box
                nonlocal grasped
                grasped = grasped or (message.topic.endswith("/events") and message.data.get("kind") == "grasp")
                if grasped and message.topic.endswith("/tf"):
                    after_grasp.append(message)
                return len(after_grasp) >= 5

            received = client.receive_until(grasped_then_moved, timeout_s=90.0)
    finally:
        code = session.close()
    assert code == 0, node.output()
    topics = {m.topic.rsplit("/", 1)[-1] for m in received}
    assert {"scene", "links", "tf", "arm", "joint_states", "landmarks", "events"} <= topics
    scene = next(m for m in received if m.topic.endswith("/scene"))
    assert {e["id"] for e in scene.data["entities"]} == {"bounds", "obstacles", "supports", "start", "goal"}
    world = load_spatial_world(params)
    states = [m for m in received if m.topic.endswith("/joint_states")]
    assert len(states) >= 2
    joints = [j["position"] for j in states[-1].data["joints"][:-1]]
    stamp = states[-1].data["timestamp"]  # the transforms of the same sample
    (transforms,) = [
        m.data["transforms"]
        for m in received
        if m.topic.endswith("/tf") and m.data["transforms"][0]["timestamp"] == stamp
    ]
    poses = world.robot.link_poses(joints)
    for t in transforms:
        if t["child_frame_id"] in poses:
            v, q = t["translation"], t["rotation"]
            placed = quaternion_matrix([v["x"], v["y"], v["z"]], [q["x"], q["y"], q["z"], q["w"]])
            np.testing.assert_allclose(placed, poses[t["child_frame_id"]], atol=1e-6)
