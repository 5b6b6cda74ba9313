"""config/foxglove_layout.json's 3-D panel for spatial arms, opened on a recorded spatial run (the Panda
witness recorded as the node records it) and on clew_plan's live view of a spatial world: every topic it
names is there, and the arm it draws (``world_markers``' ``robot_links``, each in its link's frame) is
placed by the recorded /tf and /tf_static."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

pytest.importorskip("rclpy")
pytest.importorskip("urdf_parser_py")

from helpers.spatial_recording import NODE, record_witness

from clew_ros.recording import Recording

LAYOUT = Path(__file__).resolve().parents[2] / "config" / "foxglove_layout.json"


@pytest.fixture(scope="module")
def panel() -> dict:
    layout = json.loads(LAYOUT.read_text())
    return layout["configById"]["3D!clew_spatial"]


def test_the_spatial_panel_finds_its_topics_and_frames_in_a_spatial_recording(panel: dict, tmp_path: Path) -> None:
    recording = Recording(record_witness(tmp_path))
    named = set(re.findall(r"/clew_planner/[a-z_]+", json.dumps(panel)))
    assert {"/clew_planner/world_markers", "/clew_planner/scene", "/clew_planner/robot_description"} <= named
    assert named <= set(recording.topics)
    assert panel["followTf"] == "world"
    assert panel["cameraState"]["perspective"] is True
    shown = {topic for topic, config in panel["topics"].items() if config["visible"]}
    assert f"/{NODE}/world_markers" in shown
    links = [m for m in recording.last(f"/{NODE}/world_markers").markers if m.ns == "robot_links"]
    assert links
    assert all(m.frame_locked for m in links)
    placed = {
        t.child_frame_id for m in recording.decoded("/tf_static") + recording.decoded("/tf") for t in m.transforms
    }
    assert {m.header.frame_id for m in links} <= placed


def test_the_spatial_panel_shows_the_live_views_channels(panel: dict) -> None:
    pytest.importorskip("foxglove")
    pytest.importorskip("websockets")
    pytest.importorskip("google.protobuf")
    from helpers.foxglove_client import FoxgloveClient

    from clew_ros.live import LiveView

    named = {t for t in panel["topics"] if t.startswith("/clew_plan/")}
    assert {"/clew_plan/scene", "/clew_plan/links", "/clew_plan/arm"} <= named
    with LiveView(port=0, spatial=True) as view, FoxgloveClient.connect(view.port, channels=8) as client:
        advertised = {c["topic"]: c["schemaName"] for c in client.channels.values()}
    assert all(advertised[t] == "foxglove.SceneUpdate" for t in named)
