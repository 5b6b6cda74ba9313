"""clew_replay on a recorded spatial run (the Panda table-to-table witness recorded as the node records it,
test/helpers/spatial_recording.py): every message decodes with its recorded schema and the spatial topics are
played under /replay: the URDF joints' states, the 3-D world markers, the robot description, the trajectory,
and /tf and /tf_static where tf2_msgs is installed (else named on stderr as not played, and why)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

pytest.importorskip("rclpy")
pytest.importorskip("urdf_parser_py")

from helpers.spatial_recording import NODE, record_witness

from clew_ros.cli.replay import main as clew_replay
from clew_ros.recording import Recording

SPATIAL = ("joint_states", "world_markers", "robot_description", "trajectory", "object_pose", "scene", "events")


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return record_witness(tmp_path_factory.mktemp("spatial_replay"))


def test_dry_run_lists_the_spatial_topics(recorded: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert clew_replay([str(recorded), "--dry-run"]) == 0
    captured = capsys.readouterr()
    for name in SPATIAL:
        assert f"/{NODE}/{name} -> /replay/{NODE}/{name}" in captured.out
    recording = Recording(recorded)
    tf_count = len(recording.messages(["/tf"])) + len(recording.messages(["/tf_static"]))
    assert len(recording.messages(["/tf"])) > 10  # every playback sample
    if importlib.util.find_spec("tf2_msgs") is not None:
        assert "/tf -> /replay/tf" in captured.out
        assert "/tf_static -> /replay/tf_static" in captured.out
        played = len(recording.messages())
    else:
        assert "not playing /tf: message type tf2_msgs/msg/TFMessage is not installed" in captured.err
        assert "not playing /tf_static: message type tf2_msgs/msg/TFMessage is not installed" in captured.err
        played = len(recording.messages()) - tf_count
    assert f"would play {played} messages" in captured.out
