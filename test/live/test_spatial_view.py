"""The live view of a spatial world (the shipped Panda table-to-table world, its witness plan): a client on
127.0.0.1 receives the scene in 3-D, the arm's links in their own frames, the transforms that place them
(the checker's forward kinematics), and the plan played back to its end, holding the box in the transfer."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("foxglove")
pytest.importorskip("websockets")
pytest.importorskip("google.protobuf")
pytest.importorskip("urdf_parser_py")

from helpers.foxglove_client import FoxgloveClient, Received

from clew_ros.core.plan import Plan
from clew_ros.live import LiveView, LiveViewError
from clew_ros.render.spatial.frames import load_spatial_world
from clew_ros.spatial.transforms import quaternion_matrix
from clew_ros.spatial.world import SpatialWorld

CONFIG = Path(__file__).resolve().parents[2] / "config" / "spatial"
CHANNELS = 8
#: Fast playback: the witness plays in a few seconds (the URDF's velocity limits still bind).
FAST = {"max_velocity_rad_s": 20.0, "max_acceleration_rad_s2": 200.0, "grasp_dwell_s": 0.05, "rate_hz": 25.0}


@pytest.fixture(scope="module")
def world() -> SpatialWorld:
    return load_spatial_world(CONFIG / "panda_table_to_table.yaml")


@pytest.fixture
def view() -> Iterator[LiveView]:
    with LiveView(port=0, spatial=True, **FAST) as live:
        yield live


def of(messages: list[Received], name: str) -> list[Received]:
    return [m for m in messages if m.topic == f"/clew_plan/{name}"]


def frames(message: Received) -> dict[str, np.ndarray]:
    """The 4x4 pose of every child frame of a FrameTransforms message."""
    out = {}
    for t in message.data["transforms"]:
        assert t["parent_frame_id"] == "world"
        v, q = t["translation"], t["rotation"]
        out[t["child_frame_id"]] = quaternion_matrix([v["x"], v["y"], v["z"]], [q["x"], q["y"], q["z"], q["w"]])
    return out


def test_the_world_the_links_and_their_frames(view: LiveView, world: SpatialWorld) -> None:
    view.publish_world(world)
    with FoxgloveClient.connect(view.port, channels=CHANNELS) as client:
        assert view.wait_for_client(5.0)
        advertised = {c["topic"]: c["schemaName"] for c in client.channels.values()}
        received = {m.topic: m for m in (client.receive() for _ in range(5))}
    assert advertised["/clew_plan/links"] == "foxglove.SceneUpdate"
    assert advertised["/clew_plan/tf"] == "foxglove.FrameTransforms"
    assert set(received) == {f"/clew_plan/{n}" for n in ("scene", "links", "landmarks", "arm", "tf")}
    scene = {e["id"]: e for e in received["/clew_plan/scene"].data["entities"]}
    assert set(scene) == {"bounds", "obstacles", "supports", "start", "goal"}
    tables = scene["supports"]["cubes"]
    centres = sorted((c["pose"]["position"]["x"], c["pose"]["position"]["y"]) for c in tables)
    np.testing.assert_allclose(centres, [(0.5, -0.3), (0.5, 0.3)], atol=1e-9)
    assert scene["start"]["cubes"][0]["pose"]["position"]["z"] == pytest.approx(world.object.initial[2])
    links = {e["id"]: e for e in received["/clew_plan/links"].data["entities"]}
    assert set(links) == {f"link/{link.name}" for link in world.robot.links if link.geometries}
    for link in world.robot.links:
        entity = links[f"link/{link.name}"]
        assert entity["frame_id"] == link.name
        assert entity["frame_locked"] is True
        assert entity["triangles"] or entity["cubes"] or entity["cylinders"] or entity["spheres"]
    placed = frames(received["/clew_plan/tf"])
    expected = world.robot.link_poses(world.initial.tolist())
    assert set(placed) == {*expected, "object"}
    for name, pose in expected.items():
        np.testing.assert_allclose(placed[name], pose, atol=1e-6)


def test_the_plan_played_back_moves_the_links_and_carries_the_box(view: LiveView, world: SpatialWorld) -> None:
    planned = Plan.read(CONFIG / "panda_table_to_table.witness.json")
    view.publish_world(world)
    with FoxgloveClient.connect(view.port, channels=CHANNELS) as client:
        assert view.wait_for_client(5.0)
        view.publish_outcome(planned)
        assert view.play(planned)
        received = client.receive_until(
            lambda m: m.topic.endswith("/events") and m.data["kind"] == "playback_done", 60.0
        )
    kinds = [m.data["kind"] for m in of(received, "events")]
    assert kinds.count("grasp") == 1
    assert kinds[-1] == "playback_done"
    states = of(received, "joint_states")
    assert len(states) >= 10
    names = [j["name"] for j in states[-1].data["joints"]]
    assert names == [*world.robot.joint_names, "gripper"]
    last = np.array([j["position"] for j in states[-1].data["joints"][:-1]])
    np.testing.assert_allclose(last, planned.segments[-1].waypoints[-1], atol=1e-9)
    placed = frames(of(received, "tf")[-1])
    for name, pose in world.robot.link_poses(last.tolist()).items():
        np.testing.assert_allclose(placed[name], pose, atol=1e-6)
    held = [
        e["cubes"][0]["color"]
        for m in of(received, "arm")
        for e in m.data["entities"]
        if e["id"] == "object" and e["cubes"]
    ]
    assert len({(c["r"], c["g"], c["b"]) for c in held}) == 2  # at rest and held
    box = placed["object"][:3, 3]
    np.testing.assert_allclose(box, planned.final_object_pose[:3], atol=1e-6)


def test_a_view_made_for_planar_worlds_adds_the_spatial_channels(world: SpatialWorld) -> None:
    with LiveView(port=0) as live:
        live.publish_world(world)
        live.publish_spatial_sample(world.initial, 1.0, np.asarray(world.object.initial))
        with FoxgloveClient.connect(live.port, channels=CHANNELS) as client:
            received = {m.topic: m for m in (client.receive() for _ in range(5))}
    assert {"/clew_plan/links", "/clew_plan/tf"} <= set(received)
    (gripper,) = [e for e in received["/clew_plan/arm"].data["entities"] if e["id"] == "gripper"]
    assert gripper["spheres"]  # the tcp, red: holding (gripper 1.0)
    with LiveView(port=0) as live, pytest.raises(LiveViewError, match="publish_world"):
        live.publish_spatial_sample(world.initial, 0.0, None)
