"""clew_render on a recorded spatial run: the world from the recording alone (``~/world_yaml``, its robot from
``~/robot_description`` and the meshes of ``~/world_markers``), the plan rebuilt from ``~/trajectory`` and the
``succeeded`` event's segments, drawn in 3-D. The recording is the Panda table-to-table witness recorded as
the node records a run (test/helpers/spatial_recording.py); planar recordings: test_render.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image, ImageSequence

pytest.importorskip("rclpy")
pytest.importorskip("trimesh")
pytest.importorskip("urdf_parser_py")

from helpers.spatial_recording import WITNESS, record_witness

from clew_ros.cli.render import main as clew_render
from clew_ros.core.plan import Plan
from clew_ros.render.spatial.recording import spatial_recording
from clew_ros.scene.palette import colour
from clew_ros.spatial.transforms import pose_matrix


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return record_witness(tmp_path_factory.mktemp("spatial_rec"))


@pytest.fixture(scope="module")
def carried(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The same run, its ``~/world_yaml`` naming a URDF this machine does not have."""
    return record_witness(tmp_path_factory.mktemp("spatial_rec_carried"), urdf="/nowhere/panda.urdf")


def test_the_plan_is_rebuilt_from_the_recording(recorded: Path) -> None:
    run = spatial_recording(recorded)
    assert run is not None
    assert run.world_source == "world_yaml + robot_description + world_markers"
    witness = Plan.read(WITNESS)
    frames = run.frames
    np.testing.assert_allclose(frames.joints[0], witness.segments[0].waypoints[0], atol=1e-9)
    np.testing.assert_allclose(frames.joints[-1], witness.segments[-1].waypoints[-1], atol=1e-9)
    # held in the transfer only: transit, transfer, transit
    changes = np.flatnonzero(np.diff(frames.held.astype(int)))
    assert [s.kind for s in witness.segments] == ["transit", "transfer", "transit"]
    assert len(changes) == 2
    assert frames.object_poses is not None
    np.testing.assert_allclose(frames.object_poses[-1], pose_matrix(witness.final_object_pose), atol=1e-6)
    assert "succeeded" in frames.title


def test_a_recording_carried_elsewhere_draws_the_same(recorded: Path, carried: Path) -> None:
    """The robot comes from ``~/robot_description`` and the markers' meshes wherever the URDF file is."""
    run, here = spatial_recording(carried), spatial_recording(recorded)
    assert run is not None
    assert here is not None
    assert run.world.robot.joint_names == here.world.robot.joint_names
    assert [link.name for link in run.world.robot.links] == [link.name for link in here.world.robot.links]
    np.testing.assert_allclose(run.frames.joints, here.frames.joints)


def test_png_of_a_spatial_recording(recorded: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run.png"
    assert clew_render([str(recorded), "-o", str(out), "--size", "320"]) == 0, capsys.readouterr().err
    image = Image.open(out).convert("RGB")
    assert image.width == 320
    pixels = np.asarray(image).reshape(-1, 3).astype(int)
    assert len(np.unique(pixels, axis=0)) > 200  # shaded solids, not a blank canvas

    def near(key: str) -> int:
        return int(np.all(np.abs(pixels - colour(key).rgb) <= 30, axis=1).sum())

    assert near("object_rest") > 20  # the box, where the plan leaves it
    assert near("transfer") > 5  # the tcp's path while holding


def test_gif_of_a_spatial_recording(recorded: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "run.gif"
    assert clew_render([str(recorded), "-o", str(out), "--size", "160"]) == 0, capsys.readouterr().err
    frames = [np.asarray(f.convert("RGB")) for f in ImageSequence.Iterator(Image.open(out))]
    assert len(frames) > 1
    assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).sum() > 0  # the arm moved


def test_a_recording_with_frames_is_refused(recorded: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert clew_render([str(recorded), "-o", str(tmp_path / "x.png"), "--frames", str(WITNESS)]) == 2
    assert "--frames: a recording holds its plan" in capsys.readouterr().err


def test_a_planar_world_for_a_spatial_recording_is_refused(
    recorded: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    planar = Path(__file__).resolve().parents[2] / "config" / "figure1.yaml"
    assert clew_render([str(recorded), "-o", str(tmp_path / "x.png"), "--world", str(planar)]) == 2
    assert "is a planar world; the recording is of a spatial run" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_an_aborted_run_draws_the_start_and_says_so(tmp_path: Path) -> None:
    run = spatial_recording(record_witness(tmp_path, succeeded=False))
    assert run is not None
    assert len(run.frames.joints) == 1
    np.testing.assert_allclose(run.frames.joints[0], run.world.initial)
    assert "aborted: no plan within the time limit" in run.frames.title
    out = tmp_path / "aborted.png"
    assert clew_render([str(tmp_path / f"{0x45B:032x}"), "-o", str(out), "--size", "160"]) == 0
    assert out.stat().st_size > 0
