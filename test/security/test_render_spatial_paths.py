"""Security of ``clew_render`` on spatial inputs: a recording is drawn from what it holds, never from a path
named inside it (its ``~/world_yaml`` naming ``/dev/zero`` or a private file changes nothing), and the files a
user names (``--world``, ``--frames``, INPUT) are read only as regular files within their caps."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from helpers.security_spatial import SECRET, record_start

pytest.importorskip("rclpy")
pytest.importorskip("trimesh")
pytest.importorskip("urdf_parser_py")

from clew_ros.cli.render import main as clew_render
from clew_ros.planar.world import read_parameter_file
from clew_ros.render.spatial.recording import spatial_recording
from clew_ros.spatial.world import spatial_world_from_parameters

ROOT = Path(__file__).resolve().parents[2]
SCENE_WORLD = ROOT / "config" / "spatial" / "panda_scene_motion.yaml"
TABLE_WORLD = ROOT / "config" / "spatial" / "panda_table_to_table.yaml"
TIMEOUT_S = 10.0


@pytest.fixture(scope="module")
def secret_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("private") / "notes.txt"
    path.write_text(f"{SECRET}\n", encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def devices(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The scene world's start, its ``~/world_yaml`` naming ``/dev/zero`` for the URDF, SRDF and scene file."""
    names = {"urdf": "/dev/zero", "srdf": "/dev/zero", "scene_file": "/dev/zero"}
    return record_start(tmp_path_factory.mktemp("devices"), SCENE_WORLD, names)


@pytest.fixture(scope="module")
def secrets(tmp_path_factory: pytest.TempPathFactory, secret_file: Path) -> Path:
    names = {"urdf": str(secret_file), "srdf": str(secret_file), "scene_file": str(secret_file)}
    return record_start(tmp_path_factory.mktemp("secrets"), SCENE_WORLD, names)


def test_the_recorded_world_is_the_world_whatever_paths_it_names(devices: Path, secrets: Path) -> None:
    """The obstacles of the scene file come from the markers, the robot from ~/robot_description and the
    markers' meshes: the same world as the files give."""
    truth = spatial_world_from_parameters(read_parameter_file(SCENE_WORLD), SCENE_WORLD.parent)
    for recording in (devices, secrets):
        run = spatial_recording(recording)
        assert run is not None
        world = run.world
        assert world.robot.joint_names == truth.robot.joint_names
        assert [link.name for link in world.robot.links] == [link.name for link in truth.robot.links]
        assert len(world.obstacles) == len(truth.obstacles) == 4  # a table and the cage's three parts
        for got, want in zip(world.obstacles, truth.obstacles, strict=True):
            assert got.shape == want.shape
            np.testing.assert_allclose(got.size, want.size, atol=1e-9)
            np.testing.assert_allclose(got.pose, want.pose, atol=1e-9)
        np.testing.assert_allclose(world.initial, truth.initial)
        q = truth.initial.tolist()
        np.testing.assert_allclose(world.robot.tcp_pose(q), truth.robot.tcp_pose(q), atol=1e-9)


@pytest.mark.parametrize("which", ["devices", "secrets"])
def test_clew_render_draws_such_a_recording_in_its_own_process(
    which: str, request: pytest.FixtureRequest, tmp_path: Path
) -> None:
    recording = request.getfixturevalue(which)
    out = tmp_path / "run.png"
    result = subprocess.run(
        [sys.executable, "-m", "clew_ros.cli.render", str(recording), "-o", str(out), "--size", "128"],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S * 3,  # it draws: three renders' worth, the refusals below are held to 10 s
        check=False,
        cwd=ROOT,
    )
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 0
    assert SECRET not in result.stderr + result.stdout


def test_a_recording_without_its_meshes_is_refused_saying_to_pass_world(tmp_path: Path) -> None:
    """Markers without the arm's meshes: refused naming the mesh, the URDF's mesh files never opened (the
    description names the real meshes, which exist: drawing them would mean opening them)."""
    from clew_ros.render import RenderError

    recording = record_start(tmp_path, TABLE_WORLD, {"urdf": "/dev/zero"}, meshes=False)
    with pytest.raises(RenderError, match=r"not among the meshes given.*--world") as caught:
        spatial_recording(recording)
    assert "\n" not in str(caught.value)


def _fifo(tmp_path: Path, name: str) -> Path:
    path = tmp_path / name
    os.mkfifo(path)
    return path


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (lambda t: [str(TABLE_WORLD), "--frames", "/dev/zero"], "not a regular file"),
        (lambda t: [str(_fifo(t, "w.yaml"))], "not a regular file"),
        (lambda t: ["x.json", "--world", str(_fifo(t, "world.yaml"))], "not a regular file"),
        (lambda t: [str(_fifo(t, "run.mcap"))], "not a regular file"),
        (lambda t: [str(TABLE_WORLD), "--frames", str(_fifo(t, "f.json"))], "not a regular file"),
    ],
    ids=["frames /dev/zero", "world a FIFO", "--world a FIFO", "recording a FIFO", "frames a FIFO"],
)
def test_files_a_user_names_are_regular_files_only(
    argv: Callable[[Path], list[str]], expected: str, tmp_path: Path
) -> None:
    args = argv(tmp_path)
    if args[0] == "x.json":
        (tmp_path / "x.json").write_text("{}", encoding="utf-8")
        args[0] = str(tmp_path / "x.json")
    result = subprocess.run(
        [sys.executable, "-m", "clew_ros.cli.render", *args, "-o", str(tmp_path / "out.png")],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
        cwd=ROOT,
    )
    assert result.returncode == 2, result.stderr
    assert len(result.stderr.splitlines()) == 1, result.stderr
    assert expected in result.stderr, result.stderr
    assert "Traceback" not in result.stderr


def test_render_of_a_crafted_world_exits_2_without_its_contents(
    secret_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    world = tmp_path / "world.yaml"
    text = TABLE_WORLD.read_text(encoding="utf-8").replace("../robots/panda/panda.urdf", str(secret_file))
    text = text.replace("../robots/", f"{ROOT / 'config' / 'robots'}/")
    world.write_text(text, encoding="utf-8")
    assert clew_render([str(world), "-o", str(tmp_path / "w.png")]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1, err
    assert "expected URDF XML" in err
    assert SECRET not in err


def test_a_metadata_file_is_refused_without_its_contents(tmp_path: Path) -> None:
    """A run directory whose metadata.yaml is not YAML: refused with where it fails, not what it holds."""
    run = tmp_path / "run"
    run.mkdir()
    (run / "metadata.yaml").write_text(f"{SECRET}: [\n  {SECRET}\n", encoding="utf-8")
    result = subprocess.run(
        [sys.executable, "-m", "clew_ros.cli.render", str(run), "-o", str(tmp_path / "out.png")],
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
        cwd=ROOT,
    )
    assert result.returncode == 2, result.stderr
    assert "is not rosbag2 metadata" in result.stderr, result.stderr
    assert SECRET not in result.stderr


def test_a_recording_with_too_many_obstacle_markers_is_refused_before_reading_them(tmp_path: Path) -> None:
    from clew_ros.core.parameters import LIMITS
    from clew_ros.render import RenderError

    recording = record_start(tmp_path, SCENE_WORLD, {"scene_file": "/dev/zero"}, extra_markers=LIMITS.max_obstacles + 1)
    with pytest.raises(RenderError, match=r"Limits\.max_obstacles"):
        spatial_recording(recording)
